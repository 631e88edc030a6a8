// The OpenCL relight of backend `uncompressed` (compressors/uncompressed/uncompressed.cl).
#include <bit>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"
#include "uncompressed/uncompressed.h"

namespace prt::uncompressed {
namespace {

// The output buffer is read straight into LocalRadiance::values as packed RGB.
static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

// Rows variant: 64 work-items per group keeps PoCL's work-item loop short enough to stay in
// cache; lanes variant: 128 (4 warps) so a group covers 16 rows at 8 lanes.
constexpr std::size_t kRowsWorkGroup = 64;
constexpr std::size_t kLanesWorkGroup = 128;

class UncompressedDevice final : public DeviceRelighter {
 public:
  UncompressedDevice(ClContext& ctx, const TransferMatrix& t, const Options& options)
      : ctx_(ctx),
        variant_(resolve_variant(options.kernel, ctx.info())),
        rows_(t.rows()),
        cols_(t.cols()),
        dim_(t.local_count()),
        vertices_(t.vertex_count()),
        scale_(static_cast<float>(t.scale())),
        light_host_(t.cols()) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(
          fmt::format("{}: {} rows exceed the kernel's u32 row index", kName, rows_));
    const bool lanes = variant_ == KernelVariant::kLanes;
    const std::size_t wg = lanes ? kLanesWorkGroup : kRowsWorkGroup;
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", wg).set("PRT_COLUMN_T", t.narrow_columns() ? "ushort" : "uint");
    if (lanes) {
      PRT_CHECK(options.lanes >= 1 && static_cast<std::size_t>(options.lanes) <= wg &&
                    std::has_single_bit(static_cast<unsigned>(options.lanes)),
                "opencl_lanes {} is not a power of two <= {}", options.lanes, wg);
      defines.set("PRT_LANES", options.lanes);
    }
    const cl::Program program = build_program(ctx, "uncompressed", defines);
    kernel_ = make_kernel(program, lanes ? "uncompressed_lanes" : "uncompressed_rows");
    launch_name_ = lanes ? "uncompressed.lanes" : "uncompressed.rows";
    range_ = lanes ? LaunchRange::linear(rows_ * static_cast<std::size_t>(options.lanes), wg)
                   : LaunchRange::linear(rows_, wg);

    offsets_ = upload(ctx, t.row_offsets(), "uncompressed row offsets");
    if (t.narrow_columns()) {
      columns_ = upload(ctx, t.columns16(), "uncompressed column ids");
    } else {
      columns_ = upload(ctx, t.columns32(), "uncompressed column ids");
    }
    counts_ = upload(ctx, t.counts(), "uncompressed counts");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "uncompressed light");
    out_ = make_buffer(ctx, rows_ * sizeof(Rgb), CL_MEM_WRITE_ONLY, "uncompressed local radiance");
    bytes_ = buffer_bytes({&offsets_, &columns_, &counts_, &light_, &out_});
    set_args(kernel_, static_cast<cl_uint>(rows_), scale_, offsets_, columns_, counts_, light_,
             out_);
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "uncompressed light");
    if (rows_ == 0) return 0.0;  // OpenCL forbids an empty launch
    cl::Event event = launch(ctx_, launch_name_, kernel_, range_);
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel " + launch_name_);
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    if (out.basis != RadianceBasis::kPixel || out.dim != dim_ || out.vertices != vertices_ ||
        out.values.size() != rows_) {
      out = LocalRadiance(RadianceBasis::kPixel, dim_, vertices_);
    }
    download(ctx_, out_, std::span<Rgb>(out.values), "uncompressed local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  ClContext& ctx_;
  KernelVariant variant_;
  std::size_t rows_, cols_;
  int dim_;
  std::size_t vertices_;
  float scale_;
  std::vector<cl_float4> light_host_;
  cl::Kernel kernel_;
  std::string launch_name_;
  LaunchRange range_;
  cl::Buffer offsets_, columns_, counts_, light_, out_;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_transfer(ClContext& context, const TransferMatrix& transfer,
                                                 const Options& options) {
  return std::make_unique<UncompressedDevice>(context, transfer, options);
}

}  // namespace prt::uncompressed
