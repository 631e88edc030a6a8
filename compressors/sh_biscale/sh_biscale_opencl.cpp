// The OpenCL relight of backend `sh_biscale` (compressors/sh_biscale/sh_biscale.cl).
#include <fmt/format.h>

#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"
#include "sh_biscale/sh_biscale.h"

namespace prt::sh_biscale {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

constexpr std::size_t kWorkGroup = 64;

class ShBiscaleDevice final : public DeviceRelighter {
 public:
  ShBiscaleDevice(ClContext& ctx, const ShBiscaleArrays& a, std::string light_basis)
      : ctx_(ctx),
        vertices_(a.vertices),
        n_(static_cast<std::size_t>(a.n())),
        light_basis_(std::move(light_basis)),
        light_host_(n_) {
    if (a.matrices.size() > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(fmt::format("{}: {} matrix values exceed the kernels' u32 indices",
                                       kName, a.matrices.size()));
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup);
    const cl::Program program = build_program(ctx, "sh_biscale", defines);
    rows_ = make_kernel(program, "sh_biscale_rows");
    rows_vertices_ = make_kernel(program, "sh_biscale_rows_vertices");
    static const float kDummy[1] = {0.f};
    matrices_ = a.matrices.empty()
                    ? upload(ctx, std::span<const float>(kDummy), "sh_biscale matrices")
                    : upload(ctx, std::span<const float>(a.matrices), "sh_biscale matrices");
    light_ = make_buffer(ctx, n_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "sh_biscale light");
    out_ = make_buffer(ctx, std::max<std::size_t>(1, vertices_ * n_) * sizeof(Rgb),
                       CL_MEM_READ_WRITE, "sh_biscale local radiance");
    set_args(rows_, static_cast<cl_uint>(vertices_ * n_), static_cast<cl_uint>(n_), matrices_,
             light_, out_);
    bytes_ = buffer_bytes({&matrices_, &light_, &out_});
  }

  bool supports_vertex_subset() const override { return true; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    put_light(light);
    const std::size_t items = subset_.size() * n_;
    if (items == 0) return 0.0;
    set_args(rows_vertices_, static_cast<cl_uint>(items), static_cast<cl_uint>(n_),
             subset_.buffer(), matrices_, light_, out_);
    cl::Event event = launch(ctx_, "sh_biscale.rows_vertices", rows_vertices_,
                             LaunchRange::linear(items, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name,
                              "timing of kernel sh_biscale.rows_vertices");
  }

  double relight_on_device(const LightCoeffs& light) override {
    put_light(light);
    const std::size_t items = vertices_ * n_;
    if (items == 0) return 0.0;
    cl::Event event =
        launch(ctx_, "sh_biscale.rows", rows_, LaunchRange::linear(items, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel sh_biscale.rows");
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kSphericalHarmonics, static_cast<int>(n_), vertices_);
    if (!out.values.empty())
      download(ctx_, out_, std::span<Rgb>(out.values), "sh_biscale local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  void put_light(const LightCoeffs& light) {
    if (light.basis != light_basis_ || light.values.size() != n_)
      throw ParameterError(fmt::format(
          "{}: the light is in basis '{}' with {} values, the transfer needs '{}' with {}", kName,
          light.basis, light.values.size(), light_basis_, n_));
    upload_light(ctx_, light_, light.values, light_host_, "sh_biscale light");
  }

  ClContext& ctx_;
  std::size_t vertices_, n_;
  std::string light_basis_;
  std::vector<cl_float4> light_host_;
  cl::Kernel rows_, rows_vertices_;
  cl::Buffer matrices_, light_, out_;
  std::uint64_t bytes_ = 0;
  DeviceIdList subset_{"sh_biscale vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_sh_biscale(ClContext& context, const ShBiscaleArrays& a,
                                                   const std::string& light_basis) {
  return std::make_unique<ShBiscaleDevice>(context, a, light_basis);
}

}  // namespace prt::sh_biscale
