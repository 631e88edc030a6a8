// The OpenCL relight of backend `bicluster` (kernels/bicluster.cl): two launches per relight.
#include <limits>

#include "bicluster/bicluster.h"
#include "prtlab/cl_runtime.h"
#include "prtlab/error.h"

namespace prt::bicluster {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

// 64 work-items per group, as the `uncompressed` rows kernel (short PoCL work-item loops).
constexpr std::size_t kWorkGroup = 64;

template <typename T>
cl::Buffer upload_nonempty(ClContext& ctx, const std::vector<T>& v, const char* what) {
  // A zero-sized buffer is invalid in OpenCL: keep one dummy element.
  if (v.empty()) {
    const std::vector<T> one(1, T{});
    return upload(ctx, std::span<const T>(one), what);
  }
  return upload(ctx, std::span<const T>(v), what);
}

cl::Buffer upload_columns(ClContext& ctx, const std::vector<std::uint32_t>& c, bool narrow,
                          const char* what) {
  if (narrow) return upload_nonempty(ctx, std::vector<std::uint16_t>(c.begin(), c.end()), what);
  return upload_nonempty(ctx, c, what);
}

double event_ms(ClContext& ctx, cl::Event& event, const std::string& name) {
  return cl_call(ctx.info().device_name, "timing of kernel " + name, [&] {
    event.wait();
    const auto start = event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    const auto end = event.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    return static_cast<double>(end - start) * 1e-6;
  });
}

class BiclusterDevice final : public DeviceRelighter {
 public:
  BiclusterDevice(ClContext& ctx, const BiclusterArrays& a)
      : ctx_(ctx),
        rows_(a.rows()),
        cols_(static_cast<std::size_t>(a.pixel_count)),
        biclusters_(a.bicluster_count()),
        dim_(a.local_count),
        vertices_(a.vertices),
        light_host_(cols_) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max() ||
        biclusters_ > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(fmt::format("{}: {} rows / {} biclusters exceed the kernels' u32 ids",
                                       kName, rows_, biclusters_));
    const bool narrow = a.pixel_count <= 65536;
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup).set("PRT_COLUMN_T", narrow ? "ushort" : "uint");
    const cl::Program program = build_program(ctx, "bicluster", defines);
    phase1_ = make_kernel(program, "bicluster_phase1");
    phase2_ = make_kernel(program, "bicluster_phase2");
    range1_ = LaunchRange::linear(biclusters_, kWorkGroup);
    range2_ = LaunchRange::linear(rows_, kWorkGroup);

    col_offsets_ = upload_nonempty(ctx, a.bic_col_offsets, "bicluster column offsets");
    columns_ = upload_columns(ctx, a.bic_columns, narrow, "bicluster columns");
    constants_ = upload_nonempty(ctx, a.bic_constants, "bicluster constants");
    row_offsets_ = upload_nonempty(ctx, a.row_bic_offsets, "bicluster row offsets");
    row_bics_ = upload_nonempty(ctx, a.row_bics, "bicluster row ids");
    res_offsets_ = upload_nonempty(ctx, a.res_offsets, "bicluster residual offsets");
    res_columns_ = upload_columns(ctx, a.res_columns, narrow, "bicluster residual columns");
    res_counts_ = upload_nonempty(ctx, a.res_counts, "bicluster residual counts");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "bicluster light");
    products_ = make_buffer(ctx, std::max<std::size_t>(biclusters_, 1) * sizeof(cl_float4),
                            CL_MEM_READ_WRITE, "bicluster products");
    out_ = make_buffer(ctx, std::max<std::size_t>(rows_, 1) * sizeof(Rgb), CL_MEM_WRITE_ONLY,
                       "bicluster local radiance");
    const std::uint64_t cb = narrow ? 2 : 4;
    bytes_ = a.bic_col_offsets.size() * 4 + a.bic_columns.size() * cb + a.bic_constants.size() * 2 +
             a.row_bic_offsets.size() * 4 + a.row_bics.size() * 4 + a.res_offsets.size() * 4 +
             a.res_columns.size() * cb + a.res_counts.size() * 2 + cols_ * sizeof(cl_float4) +
             biclusters_ * sizeof(cl_float4) + rows_ * sizeof(Rgb);
    set_args(phase1_, static_cast<cl_uint>(biclusters_), col_offsets_, columns_, constants_, light_,
             products_);
    set_args(phase2_, static_cast<cl_uint>(rows_), static_cast<float>(a.scale()), row_offsets_,
             row_bics_, products_, res_offsets_, res_columns_, res_counts_, light_, out_);
  }

  double relight_on_device(const LightCoeffs& light) override {
    if (light.basis != "pixel" || light.values.size() != cols_) {
      throw ParameterError(fmt::format(
          "{}: relight needs a pixel-basis light of N = {} values, got basis '{}' with {}", kName,
          cols_, light.basis, light.values.size()));
    }
    for (std::size_t k = 0; k < cols_; ++k)
      light_host_[k] = cl_float4{{light.values[k].x, light.values[k].y, light.values[k].z, 0.f}};
    write_buffer(ctx_, light_, light_host_.data(), light_host_.size() * sizeof(cl_float4),
                 "bicluster light");
    double ms = 0.0;
    // OpenCL forbids empty launches; the in-order queue orders phase 2 after phase 1.
    if (biclusters_ > 0) {
      cl::Event e1 = launch(ctx_, "bicluster.phase1", phase1_, range1_);
      ms += event_ms(ctx_, e1, "bicluster.phase1");
    }
    if (rows_ > 0) {
      cl::Event e2 = launch(ctx_, "bicluster.phase2", phase2_, range2_);
      ms += event_ms(ctx_, e2, "bicluster.phase2");
    }
    return ms;
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    if (out.basis != RadianceBasis::kPixel || out.dim != dim_ || out.vertices != vertices_ ||
        out.values.size() != rows_) {
      out = LocalRadiance(RadianceBasis::kPixel, dim_, vertices_);
    }
    if (rows_ > 0) download(ctx_, out_, std::span<Rgb>(out.values), "bicluster local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }

 private:
  ClContext& ctx_;
  std::size_t rows_, cols_, biclusters_;
  int dim_;
  std::size_t vertices_;
  std::vector<cl_float4> light_host_;
  cl::Kernel phase1_, phase2_;
  LaunchRange range1_, range2_;
  cl::Buffer col_offsets_, columns_, constants_, row_offsets_, row_bics_, res_offsets_,
      res_columns_, res_counts_, light_, products_, out_;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_arrays(ClContext& context, const BiclusterArrays& a) {
  return std::make_unique<BiclusterDevice>(context, a);
}

}  // namespace prt::bicluster
