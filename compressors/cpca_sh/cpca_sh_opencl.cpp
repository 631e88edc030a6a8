// The OpenCL relight of backend `cpca_sh` (compressors/cpca_sh/cpca_sh.cl).
#include <fmt/format.h>

#include <limits>

#include "cpca_sh/cpca_sh.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::cpca_sh {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

constexpr std::size_t kWorkGroup = 64;

std::string_view id_type(std::size_t bytes) {
  return bytes == 1 ? "uchar" : (bytes == 2 ? "ushort" : "uint");
}

int weight_format_code(WeightFormat f) {
  return f == WeightFormat::kFloat32 ? 0 : (f == WeightFormat::kFloat16 ? 1 : 2);
}

class CpcaShDevice final : public DeviceRelighter {
 public:
  CpcaShDevice(ClContext& ctx, const CpcaShArrays& a, std::string light_basis)
      : ctx_(ctx),
        vertices_(a.vertices),
        rows_(static_cast<std::size_t>(a.rows())),
        n_(static_cast<std::size_t>(a.n())),
        products_count_(a.rep_count() * rows_),
        light_basis_(std::move(light_basis)),
        light_host_(n_),
        light_scale_(a.light_scale()) {
    if (vertices_ * rows_ > std::numeric_limits<std::uint32_t>::max() ||
        a.reps.size() > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(
          fmt::format("{}: {} vertices or {} representative values exceed the "
                      "kernels' u32 indices",
                      kName, vertices_, a.reps.size()));
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_ID_T", id_type(a.id_bytes()))
        .set("PRT_WEIGHT_FORMAT", weight_format_code(a.format));
    const cl::Program program = build_program(ctx, "cpca_sh", defines);
    products_kernel_ = make_kernel(program, "cpca_sh_products");
    blend_ = make_kernel(program, "cpca_sh_blend");
    blend_vertices_ = make_kernel(program, "cpca_sh_blend_vertices");

    switch (a.id_bytes()) {
      case 1: {
        const std::vector<std::uint8_t> ids(a.ids.begin(), a.ids.end());
        ids_ = upload(ctx, std::span<const std::uint8_t>(ids), "cpca_sh cluster ids");
        break;
      }
      case 2: {
        const std::vector<std::uint16_t> ids(a.ids.begin(), a.ids.end());
        ids_ = upload(ctx, std::span<const std::uint16_t>(ids), "cpca_sh cluster ids");
        break;
      }
      default:
        ids_ = upload(ctx, std::span<const std::uint32_t>(a.ids), "cpca_sh cluster ids");
    }
    first_ = upload(ctx, std::span<const std::uint32_t>(a.first), "cpca_sh representative offsets");
    offsets_ = upload(ctx, std::span<const std::uint32_t>(a.weight_offsets),
                      "cpca_sh vertex weight offsets");
    // A zero-length buffer is not allowed: empty weight arrays get one dummy element.
    static const float kDummy[1] = {0.f};
    static const std::uint16_t kDummyHalf[1] = {0};
    static const std::int8_t kDummyCode[1] = {0};
    switch (a.format) {
      case WeightFormat::kFloat32:
        weights_ = a.weights32.empty()
                       ? upload(ctx, std::span<const float>(kDummy), "cpca_sh weights")
                       : upload(ctx, std::span<const float>(a.weights32), "cpca_sh weights");
        break;
      case WeightFormat::kFloat16:
        weights_ =
            a.weights16.empty()
                ? upload(ctx, std::span<const std::uint16_t>(kDummyHalf), "cpca_sh weights")
                : upload(ctx, std::span<const std::uint16_t>(a.weights16), "cpca_sh weights");
        break;
      case WeightFormat::kS8:
        weights_ = a.codes.empty()
                       ? upload(ctx, std::span<const std::int8_t>(kDummyCode), "cpca_sh weights")
                       : upload(ctx, std::span<const std::int8_t>(a.codes), "cpca_sh weights");
        break;
    }
    scales_ = a.vertex_scales.empty()
                  ? upload(ctx, std::span<const float>(kDummy), "cpca_sh vertex scales")
                  : upload(ctx, std::span<const float>(a.vertex_scales), "cpca_sh vertex scales");
    representatives_ = upload(ctx, std::span<const float>(a.reps), "cpca_sh representatives");
    products_ = make_buffer(ctx, products_count_ * sizeof(cl_float4), CL_MEM_READ_WRITE,
                            "cpca_sh products");
    light_ = make_buffer(ctx, n_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "cpca_sh light");
    out_ = make_buffer(ctx, vertices_ * rows_ * sizeof(Rgb), CL_MEM_READ_WRITE,
                       "cpca_sh local radiance");
    subset_ = make_buffer(ctx, 0, CL_MEM_READ_ONLY, "cpca_sh vertex subset");
    set_args(products_kernel_, static_cast<cl_uint>(products_count_), static_cast<cl_uint>(n_),
             representatives_, light_, products_);
    set_args(blend_, static_cast<cl_uint>(vertices_ * rows_), static_cast<cl_uint>(rows_), ids_,
             first_, offsets_, weights_, scales_, products_, out_);
    bytes_ = buffer_bytes({&ids_, &first_, &offsets_, &weights_, &scales_, &representatives_,
                           &products_, &light_, &out_});
  }

  bool supports_vertex_subset() const override { return true; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    subset_count_ = vertices.size();
    if (vertices.size_bytes() > subset_capacity_) {
      subset_capacity_ = vertices.size_bytes();
      subset_ = make_buffer(ctx_, subset_capacity_, CL_MEM_READ_ONLY, "cpca_sh vertex subset");
    }
    if (!vertices.empty())
      write_buffer(ctx_, subset_, vertices.data(), vertices.size_bytes(), "cpca_sh vertex subset");
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    const double ms = products(light);
    const std::size_t items = subset_count_ * rows_;
    if (items == 0) return ms;
    set_args(blend_vertices_, static_cast<cl_uint>(items), static_cast<cl_uint>(rows_), subset_,
             ids_, first_, offsets_, weights_, scales_, products_, out_);
    cl::Event event = launch(ctx_, "cpca_sh.blend_vertices", blend_vertices_,
                             LaunchRange::linear(items, kWorkGroup));
    return ms + event_milliseconds(event, ctx_.info().device_name,
                                   "timing of kernel cpca_sh.blend_vertices");
  }

  double relight_on_device(const LightCoeffs& light) override {
    const double ms = products(light);
    const std::size_t items = vertices_ * rows_;
    if (items == 0) return ms;
    cl::Event event = launch(ctx_, "cpca_sh.blend", blend_, LaunchRange::linear(items, kWorkGroup));
    return ms +
           event_milliseconds(event, ctx_.info().device_name, "timing of kernel cpca_sh.blend");
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    const int dim = static_cast<int>(rows_);
    if (out.basis != RadianceBasis::kSphericalHarmonics || out.dim != dim ||
        out.vertices != vertices_ || out.values.size() != vertices_ * rows_) {
      out = LocalRadiance(RadianceBasis::kSphericalHarmonics, dim, vertices_);
    }
    if (!out.values.empty())
      download(ctx_, out_, std::span<Rgb>(out.values), "cpca_sh local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  // Uploads the light and launches the per-representative products; returns kernel ms.
  double products(const LightCoeffs& light) {
    if (light.basis != light_basis_ || light.values.size() != n_)
      throw ParameterError(
          fmt::format("{}: the light is in basis '{}' with {} values, the "
                      "transfer needs '{}' with {}",
                      kName, light.basis, light.values.size(), light_basis_, n_));
    if (light_scale_ == 1.0f) {
      upload_light(ctx_, light_, light.values, light_host_, "cpca_sh light");
    } else {
      // The same float products as scaled_light() in the C++ relight.
      std::vector<Rgb> scaled(light.values);
      for (Rgb& v : scaled) v *= light_scale_;
      upload_light(ctx_, light_, scaled, light_host_, "cpca_sh light");
    }
    if (products_count_ == 0) return 0.0;
    cl::Event event = launch(ctx_, "cpca_sh.products", products_kernel_,
                             LaunchRange::linear(products_count_, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel cpca_sh.products");
  }

  ClContext& ctx_;
  std::size_t vertices_, rows_, n_, products_count_;
  std::string light_basis_;
  std::vector<cl_float4> light_host_;
  float light_scale_;
  cl::Kernel products_kernel_, blend_, blend_vertices_;
  cl::Buffer ids_, first_, offsets_, weights_, scales_, representatives_, products_, light_, out_;
  std::uint64_t bytes_ = 0;
  cl::Buffer subset_;
  std::size_t subset_count_ = 0, subset_capacity_ = 0;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_cpca_sh(ClContext& context, const CpcaShArrays& arrays,
                                                const std::string& light_basis) {
  return std::make_unique<CpcaShDevice>(context, arrays, light_basis);
}

}  // namespace prt::cpca_sh
