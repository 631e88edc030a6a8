// The OpenCL relight of backend `csr_quantized` (compressors/csr_quantized/csr_quantized.cl).
#include <limits>

#include "csr_quantized/csr_quantized.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::csr_quantized {
namespace {

// The output buffer is read straight into LocalRadiance::values as packed RGB.
static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

// One work-item per row, 64 per group: PoCL's work-item loop stays short enough to stay in
// cache (as uncompressed's rows variant).
constexpr std::size_t kWorkGroup = 64;

std::string_view kernel_name(ValueFormat f) {
  switch (f) {
    case ValueFormat::kFloat32:
      return "csr_quantized_f32";
    case ValueFormat::kFloat16:
      return "csr_quantized_f16";
    case ValueFormat::kU8:
      return "csr_quantized_u8";
  }
  return "?";
}

class CsrQuantizedDevice final : public DeviceRelighter {
 public:
  CsrQuantizedDevice(ClContext& ctx, const QuantizedCsr& q)
      : ctx_(ctx),
        rows_(q.rows()),
        cols_(static_cast<std::size_t>(q.pixel_count)),
        dim_(q.local_count),
        vertices_(q.vertices),
        format_(q.format),
        light_host_(cols_),
        launch_name_(fmt::format("csr_quantized.{}", to_string(q.format))) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(
          fmt::format("{}: {} rows exceed the kernel's u32 row index", kName, rows_));
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_COLUMN_T", q.narrow_columns() ? "ushort" : "uint");
    const cl::Program program = build_program(ctx, "csr_quantized", defines);
    kernel_ = make_kernel(program, std::string(kernel_name(q.format)));
    vertices_kernel_ = make_kernel(program, std::string(kernel_name(q.format)) + "_vertices");

    offsets_ = upload(ctx, std::span<const std::uint32_t>(q.offsets), "csr_quantized row offsets");
    if (q.narrow_columns()) {
      columns_ = upload(ctx, std::span<const std::uint16_t>(q.columns16), "csr_quantized columns");
    } else {
      columns_ = upload(ctx, std::span<const std::uint32_t>(q.columns32), "csr_quantized columns");
    }
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "csr_quantized light");
    out_ = make_buffer(ctx, rows_ * sizeof(Rgb), CL_MEM_WRITE_ONLY, "csr_quantized local radiance");
    const auto rows = static_cast<cl_uint>(rows_);
    switch (q.format) {
      case ValueFormat::kFloat32:
        values_ = upload(ctx, std::span<const float>(q.values32), "csr_quantized values");
        set_args(kernel_, rows, offsets_, columns_, values_, light_, out_);
        break;
      case ValueFormat::kFloat16:
        values_ = upload(ctx, std::span<const std::uint16_t>(q.values16), "csr_quantized values");
        set_args(kernel_, rows, offsets_, columns_, values_, light_, out_);
        break;
      case ValueFormat::kU8:
        values_ = upload(ctx, std::span<const std::uint8_t>(q.codes), "csr_quantized values");
        scales_ = upload(ctx, std::span<const float>(q.row_scales), "csr_quantized row scales");
        set_args(kernel_, rows, offsets_, columns_, values_, scales_, light_, out_);
        break;
    }
    bytes_ = q.format == ValueFormat::kU8
                 ? buffer_bytes({&offsets_, &columns_, &values_, &scales_, &light_, &out_})
                 : buffer_bytes({&offsets_, &columns_, &values_, &light_, &out_});
  }

  bool supports_vertex_subset() const override { return true; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "csr_quantized light");
    const std::size_t subset_rows = subset_.size() * static_cast<std::size_t>(dim_);
    if (subset_rows == 0) return 0.0;  // OpenCL forbids an empty launch
    const auto count = static_cast<cl_uint>(subset_rows);
    const auto dim = static_cast<cl_uint>(dim_);
    if (format_ == ValueFormat::kU8) {
      set_args(vertices_kernel_, count, dim, subset_.buffer(), offsets_, columns_, values_, scales_,
               light_, out_);
    } else {
      set_args(vertices_kernel_, count, dim, subset_.buffer(), offsets_, columns_, values_, light_,
               out_);
    }
    const std::string name = launch_name_ + ".vertices";
    cl::Event event =
        launch(ctx_, name, vertices_kernel_, LaunchRange::linear(subset_rows, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel " + name);
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "csr_quantized light");
    if (rows_ == 0) return 0.0;  // OpenCL forbids an empty launch
    cl::Event event = launch(ctx_, launch_name_, kernel_, LaunchRange::linear(rows_, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel " + launch_name_);
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, dim_, vertices_);
    download(ctx_, out_, std::span<Rgb>(out.values), "csr_quantized local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  ClContext& ctx_;
  std::size_t rows_, cols_;
  int dim_;
  std::size_t vertices_;
  ValueFormat format_;
  std::vector<cl_float4> light_host_;
  std::string launch_name_;
  cl::Kernel kernel_;
  cl::Buffer offsets_, columns_, values_, scales_, light_, out_;
  std::uint64_t bytes_ = 0;
  // The vertex subset relit by relight_subset_on_device().
  cl::Kernel vertices_kernel_;
  DeviceIdList subset_{"csr_quantized vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_quantized(ClContext& context, const QuantizedCsr& arrays) {
  return std::make_unique<CsrQuantizedDevice>(context, arrays);
}

}  // namespace prt::csr_quantized
