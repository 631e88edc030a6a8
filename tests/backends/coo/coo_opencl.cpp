// The OpenCL relight of the test-only backend `coo` (coo.cl): one work-item per row, over the
// row's run of triplets; the run starts are derived at upload, not stored.
#include <limits>

#include "coo/coo.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::coo {
namespace {

constexpr std::size_t kWorkGroup = 64;

class CooDevice final : public DeviceRelighter {
 public:
  CooDevice(ClContext& ctx, const Triplets& t)
      : ctx_(ctx),
        rows_(t.vertices * static_cast<std::size_t>(t.local_count)),
        cols_(static_cast<std::size_t>(t.pixel_count)),
        dim_(t.local_count),
        vertices_(t.vertices),
        light_host_(cols_) {
    if (rows_ >= std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(fmt::format("{}: {} rows exceed u32", kName, rows_));
    std::vector<std::uint32_t> starts(rows_ + 1, 0);
    for (const auto r : t.rows) ++starts[r + 1];
    for (std::size_t i = 0; i < rows_; ++i) starts[i + 1] += starts[i];
    const cl::Program program =
        build_program(ctx, "coo", KernelDefines().set("PRT_WG_SIZE", kWorkGroup));
    kernel_ = make_kernel(program, "coo_relight");
    starts_ = upload(ctx, std::span<const std::uint32_t>(starts), "coo row starts");
    columns_ = upload(ctx, std::span<const std::uint32_t>(t.columns), "coo columns");
    values_ = upload(ctx, std::span<const float>(t.values), "coo values");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "coo light");
    out_ = make_buffer(ctx, std::max<std::size_t>(rows_, 1) * sizeof(Rgb), CL_MEM_WRITE_ONLY,
                       "coo local radiance");
    bytes_ = buffer_bytes({&starts_, &columns_, &values_, &light_, &out_});
    set_args(kernel_, static_cast<cl_uint>(rows_), starts_, columns_, values_, light_, out_);
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "coo light");
    if (rows_ == 0) return 0.0;
    cl::Event event = launch(ctx_, "coo.relight", kernel_, LaunchRange::linear(rows_, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel coo.relight");
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out = LocalRadiance(RadianceBasis::kPixel, dim_, vertices_);
    if (rows_ > 0) download(ctx_, out_, std::span<Rgb>(out.values), "coo local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  ClContext& ctx_;
  std::size_t rows_, cols_;
  int dim_;
  std::size_t vertices_;
  std::vector<cl_float4> light_host_;
  cl::Kernel kernel_;
  cl::Buffer starts_, columns_, values_, light_, out_;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_triplets(ClContext& context, const Triplets& t) {
  return std::make_unique<CooDevice>(context, t);
}

}  // namespace prt::coo
