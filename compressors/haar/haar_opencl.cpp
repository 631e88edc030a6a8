// The OpenCL relight of backend `haar` (compressors/haar/haar.cl): the light's transform, then
// the rows' sparse dot products, both on the device; only the pixel light travels per relight.
// A light the host has approximated in the wavelet basis (haar_light.h) travels as its N
// coefficients and only the product kernel runs: the row kernel, or with opencl_order=columns
// the column kernel over the light's non-zero terms (haar_columns.h).
#include <limits>
#include <numeric>

#include "haar/haar.h"
#include "haar/haar_columns.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::haar {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

// One work-item per row, 64 per group, as csr_quantized: PoCL's work-item loop stays in cache.
constexpr std::size_t kWorkGroup = 64;
// Rows of a column block (opencl_order=columns): 2,048 float4 sums are 32 KB of local memory,
// within the 32 KB OpenCL 1.2 guarantees.
constexpr std::size_t kColumnBlockRows = 2048;

// The suffix of haar.cl's row kernels for a value format.
const char* kernel_suffix(ValueFormat f) {
  switch (f) {
    case ValueFormat::kFloat32:
      return "f32";
    case ValueFormat::kFloat16:
      return "f16";
    case ValueFormat::kS8:
      return "s8";
  }
  return "?";
}

class HaarDevice final : public DeviceRelighter {
 public:
  HaarDevice(ClContext& ctx, const HaarArrays& a, DeviceOrder order)
      : ctx_(ctx),
        order_(order),
        rows_(a.rows()),
        cols_(static_cast<std::size_t>(a.pixel_count)),
        dim_(a.local_count),
        vertices_(a.vertices),
        light_host_(cols_),
        rows_name_(fmt::format("haar.rows_{}", kernel_suffix(a.format))),
        scaled_(a.format == ValueFormat::kS8) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(
          fmt::format("{}: {} rows exceed the kernel's u32 row index", kName, rows_));
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_RES", a.resolution)
        .set("PRT_INDEX_T", a.wide ? "uint" : "ushort")
        .set("PRT_BLOCK_ROWS", kColumnBlockRows);
    const cl::Program program = build_program(ctx, "haar", defines);
    const std::string rows_kernel = fmt::format("haar_rows_{}", kernel_suffix(a.format));
    light_kernel_ = make_kernel(program, "haar_light");
    rows_kernel_ = make_kernel(program, rows_kernel);
    subset_kernel_ = make_kernel(program, rows_kernel + "_vertices");

    offsets_ = upload(ctx, std::span<const std::uint32_t>(a.offsets), "haar row offsets");
    // A zero-length buffer is not allowed: a transfer without terms gets one dummy element.
    static const std::uint32_t kDummy[1] = {0};
    const auto upload_or_dummy = [&](auto span, const char* what) {
      using T = typename decltype(span)::value_type;
      if (span.empty()) return upload(ctx, std::span<const std::uint32_t>(kDummy), what);
      return upload(ctx, std::span<const T>(span), what);
    };
    indices_ = a.wide
                   ? upload_or_dummy(std::span<const std::uint32_t>(a.indices32), "haar indices")
                   : upload_or_dummy(std::span<const std::uint16_t>(a.indices16), "haar indices");
    switch (a.format) {
      case ValueFormat::kFloat32:
        values_ = upload_or_dummy(std::span<const float>(a.values32), "haar values");
        break;
      case ValueFormat::kFloat16:
        values_ = upload_or_dummy(std::span<const std::uint16_t>(a.values16), "haar values");
        break;
      case ValueFormat::kS8:
        values_ = upload_or_dummy(std::span<const std::int8_t>(a.codes), "haar values");
        break;
    }
    scales_ = upload_or_dummy(std::span<const float>(a.row_scales), "haar row scales");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "haar light");
    coefficients_ =
        make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_WRITE, "haar light coefficients");
    out_ = make_buffer(ctx, std::max<std::size_t>(rows_, 1) * sizeof(Rgb), CL_MEM_READ_WRITE,
                       "haar local radiance");
    set_args(light_kernel_, static_cast<cl_uint>(cols_), light_, coefficients_);
    set_args(rows_kernel_, static_cast<cl_uint>(rows_), offsets_, indices_, values_, scales_,
             coefficients_, out_);
    if (order_ == DeviceOrder::kColumns) {
      // The column layout replaces the row arrays on the device (derived here, never stored).
      const HaarColumns columns(a, kColumnBlockRows);
      blocks_ = columns.blocks();
      offsets_ = upload_or_dummy(columns.offsets(), "haar column offsets");
      indices_ = upload_or_dummy(columns.rows_in_block(), "haar column rows");
      values_ = upload_or_dummy(columns.values(), "haar column values");
      std::vector<std::uint32_t> every(cols_);
      std::iota(every.begin(), every.end(), 0u);
      all_columns_ = upload(ctx, std::span<const std::uint32_t>(every), "haar every column");
      kept_ = make_buffer(ctx, cols_ * sizeof(std::uint32_t), CL_MEM_READ_ONLY,
                          "haar kept light terms");
      columns_kernel_ = make_kernel(program, "haar_columns");
    }
    bytes_ = buffer_bytes({&offsets_, &indices_, &values_, &scales_, &light_, &coefficients_, &out_,
                           &all_columns_, &kept_});
  }

  // The column order writes whole blocks: it never relights a subset alone.
  bool supports_vertex_subset() const override { return order_ == DeviceOrder::kRows; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    if (order_ == DeviceOrder::kColumns) return relight_on_device(light);
    const double ms = transform(light);
    const std::size_t subset_rows = subset_.size() * static_cast<std::size_t>(dim_);
    if (subset_rows == 0) return ms;  // OpenCL forbids an empty launch
    set_args(subset_kernel_, static_cast<cl_uint>(subset_rows), static_cast<cl_uint>(dim_),
             subset_.buffer(), offsets_, indices_, values_, scales_, coefficients_, out_);
    const std::string name = rows_name_ + "_vertices";
    cl::Event event =
        launch(ctx_, name, subset_kernel_, LaunchRange::linear(subset_rows, kWorkGroup));
    return ms + event_milliseconds(event, ctx_.info().device_name, "timing of kernel " + name);
  }

  double relight_on_device(const LightCoeffs& light) override {
    const double ms = transform(light);
    if (rows_ == 0) return ms;
    if (order_ == DeviceOrder::kColumns) {
      set_args(columns_kernel_, static_cast<cl_uint>(rows_), static_cast<cl_uint>(cols_),
               static_cast<cl_uint>(kept_count_), kept_count_ == cols_ ? all_columns_ : kept_,
               coefficients_, offsets_, indices_, values_, scales_,
               static_cast<cl_uint>(scaled_ ? 1 : 0), out_);
      cl::Event event = launch(ctx_, "haar.columns", columns_kernel_,
                               LaunchRange::linear(blocks_ * kWorkGroup, kWorkGroup));
      return ms +
             event_milliseconds(event, ctx_.info().device_name, "timing of kernel haar.columns");
    }
    cl::Event event =
        launch(ctx_, rows_name_, rows_kernel_, LaunchRange::linear(rows_, kWorkGroup));
    return ms +
           event_milliseconds(event, ctx_.info().device_name, "timing of kernel " + rows_name_);
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, dim_, vertices_);
    download(ctx_, out_, std::span<Rgb>(out.values), "haar local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  // Uploads the pixel light and transforms it on the device; returns kernel ms. A wavelet-basis
  // light (the host's truncation, haar_light.h) is already what the row kernels read: it goes
  // straight into the coefficient buffer and no kernel runs.
  double transform(const LightCoeffs& light) {
    if (check_light(light, cols_)) {
      upload_light(ctx_, coefficients_, light.values, light_host_, "haar light coefficients");
      if (order_ == DeviceOrder::kColumns) {
        // The column order reads only the light's non-zero terms (what the truncation kept).
        const SparseLight kept = sparse_terms(light.values);
        kept_count_ = kept.indices.size();
        if (kept_count_ > 0 && kept_count_ < cols_)
          write_buffer(ctx_, kept_, kept.indices.data(), kept_count_ * sizeof(std::uint32_t),
                       "haar kept light terms");
      }
      return 0.0;
    }
    kept_count_ = cols_;
    upload_light(ctx_, light_, light.values, light_host_, "haar light");
    cl::Event event =
        launch(ctx_, "haar.light", light_kernel_, LaunchRange::linear(cols_, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel haar.light");
  }

  ClContext& ctx_;
  DeviceOrder order_;
  std::size_t rows_, cols_;
  int dim_;
  std::size_t vertices_;
  std::vector<cl_float4> light_host_;
  std::string rows_name_;
  cl::Kernel light_kernel_, rows_kernel_, subset_kernel_, columns_kernel_;
  cl::Buffer offsets_, indices_, values_, scales_, light_, coefficients_, out_;
  cl::Buffer all_columns_, kept_;  // opencl_order=columns: the light terms to read
  std::size_t blocks_ = 0, kept_count_ = 0;
  bool scaled_ = false;
  std::uint64_t bytes_ = 0;
  DeviceIdList subset_{"haar vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_haar(ClContext& context, const HaarArrays& arrays,
                                             DeviceOrder order) {
  return std::make_unique<HaarDevice>(context, arrays, order);
}

}  // namespace prt::haar
