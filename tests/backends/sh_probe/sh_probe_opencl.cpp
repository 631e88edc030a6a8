// The OpenCL relight of the test-only backend `sh_probe` (sh_probe.cl).
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "sh_probe/sh_probe.h"

namespace prt::sh_probe {
namespace {

constexpr std::size_t kWorkGroup = 64;

class ShProbeDevice final : public DeviceRelighter {
 public:
  ShProbeDevice(ClContext& ctx, const ShProbeTransfer& p)
      : ctx_(ctx),
        vertices_(p.matrix().vertex_count()),
        cols_(p.matrix().cols()),
        n_(sh_count(p.order())) {
    const TransferMatrix& t = p.matrix();
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_COLUMN_T", t.narrow_columns() ? "ushort" : "uint")
        .set("PRT_SH_COUNT", n_)
        .set("PRT_LOCAL_COUNT", t.local_count());
    kernel_ = make_kernel(build_program(ctx, "sh_probe", defines), "sh_probe_relight");
    offsets_ = upload(ctx, t.row_offsets(), "sh_probe row offsets");
    if (t.narrow_columns())
      columns_ = upload(ctx, t.columns16(), "sh_probe columns");
    else
      columns_ = upload(ctx, t.columns32(), "sh_probe columns");
    counts_ = upload(ctx, t.counts(), "sh_probe counts");
    projection_ = upload(ctx, std::span<const float>(p.projection()), "sh_probe projection");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "sh_probe light");
    out_ = make_buffer(ctx, vertices_ * n_ * sizeof(Rgb), CL_MEM_WRITE_ONLY, "sh_probe output");
    set_args(kernel_, static_cast<cl_uint>(vertices_), static_cast<float>(t.scale()), offsets_,
             columns_, counts_, projection_, light_, out_);
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "sh_probe light");
    if (vertices_ == 0) return 0.0;
    cl::Event e =
        launch(ctx_, "sh_probe.relight", kernel_, LaunchRange::linear(vertices_, kWorkGroup));
    return event_milliseconds(e, ctx_.info().device_name, "timing of kernel sh_probe.relight");
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out = LocalRadiance(RadianceBasis::kSphericalHarmonics, n_, vertices_);
    if (!out.values.empty()) download(ctx_, out_, std::span<Rgb>(out.values), "sh_probe output");
    return ms;
  }

  std::uint64_t device_bytes() const override {
    return buffer_bytes({&offsets_, &columns_, &counts_, &projection_, &light_, &out_});
  }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  ClContext& ctx_;
  std::size_t vertices_, cols_;
  int n_;
  std::vector<cl_float4> light_host_;
  cl::Kernel kernel_;
  cl::Buffer offsets_, columns_, counts_, projection_, light_, out_;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_probe(ClContext& context, const ShProbeTransfer& t) {
  return std::make_unique<ShProbeDevice>(context, t);
}

}  // namespace prt::sh_probe
