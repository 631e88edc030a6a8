// The OpenCL relight of backend `bicluster` (compressors/bicluster/bicluster.cl): two launches per
// relight, phase 1 a work-item per bicluster (plus one for the last zero slot's product), phase 2 a
// work-item per slice of 4 rows.
#include <limits>

#include "bicluster/bicluster.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::bicluster {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

// 64 work-items per group, as the `uncompressed` rows kernel (short PoCL work-item loops).
constexpr std::size_t kWorkGroup = 64;
// Biclusters per work-item of phase 1 (compressors/bicluster/bicluster.cl).
constexpr std::size_t kPhase1PerItem = 8;

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

// The lanes' running ids, zero-slot steps included, in the codes' positions.
std::vector<std::uint32_t> expand_ids(const BiclusterArrays& a) {
  std::vector<std::uint32_t> ids(a.slice_codes.size());
  for (std::size_t s = 0; s < a.slice_count(); ++s) {
    for (std::uint32_t lane = 0; lane < kSliceRows; ++lane) {
      std::uint32_t id = a.slice_base[s];
      for (std::uint32_t q = a.slice_offsets[s] + lane; q < a.slice_offsets[s + 1]; q += kSliceRows)
        ids[q] = id += a.slice_codes[q];
    }
  }
  return ids;
}

double event_ms(ClContext& ctx, cl::Event& event, const std::string& name) {
  return event_milliseconds(event, ctx.info().device_name, "timing of kernel " + name);
}

class BiclusterDevice final : public DeviceRelighter {
 public:
  BiclusterDevice(ClContext& ctx, const BiclusterArrays& a, DeviceIds device_ids)
      : ctx_(ctx),
        rows_(a.rows()),
        cols_(static_cast<std::size_t>(a.pixel_count)),
        biclusters_(a.bicluster_count()),
        slices_(a.slice_count()),
        dim_(a.local_count),
        vertices_(a.vertices),
        light_host_(cols_) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max() ||
        a.product_count() > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(fmt::format("{}: {} rows / {} biclusters exceed the kernels' u32 ids",
                                       kName, rows_, biclusters_));
    const bool narrow = a.pixel_count <= 65536;
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_COLUMN_T", narrow ? "ushort" : "uint")
        .set("PRT_PHASE1_PER_ITEM", kPhase1PerItem);
    const cl::Program program = build_program(ctx, "bicluster", defines);
    phase1_ = make_kernel(program, "bicluster_phase1");
    wide_ids_ =
        device_ids == DeviceIds::kU32 || (device_ids == DeviceIds::kAuto && ctx.info().is_cpu);
    phase2_ = make_kernel(program, wide_ids_ ? "bicluster_phase2_ids" : "bicluster_phase2");
    range1_ = LaunchRange::linear(biclusters_ / kPhase1PerItem + 1, kWorkGroup);
    const std::size_t products = a.product_count();
    range2_ = LaunchRange::linear(slices_, kWorkGroup);

    col_offsets_ = upload_nonempty(ctx, a.bic_col_offsets, "bicluster column offsets");
    columns_ = upload_columns(ctx, a.bic_columns, narrow, "bicluster columns");
    constants_ = upload_nonempty(ctx, a.bic_constants, "bicluster constants");
    slice_offsets_ = upload_nonempty(ctx, a.slice_offsets, "bicluster slice offsets");
    slice_rows_ = upload_nonempty(ctx, a.slice_rows, "bicluster slice rows");
    if (wide_ids_) {
      slice_codes_ = upload_nonempty(ctx, expand_ids(a), "bicluster slice ids");
    } else {
      slice_base_ = upload_nonempty(ctx, a.slice_base, "bicluster slice bases");
      slice_codes_ = upload_nonempty(ctx, a.slice_codes, "bicluster slice codes");
    }
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "bicluster light");
    products_ =
        make_buffer(ctx, products * sizeof(cl_float4), CL_MEM_READ_WRITE, "bicluster products");
    out_ = make_buffer(ctx, std::max<std::size_t>(rows_, 1) * sizeof(Rgb), CL_MEM_WRITE_ONLY,
                       "bicluster local radiance");
    bytes_ = buffer_bytes({&col_offsets_, &columns_, &constants_, &slice_offsets_, &slice_rows_,
                           &slice_base_, &slice_codes_, &light_, &products_, &out_});
    set_args(phase1_, static_cast<cl_uint>(biclusters_), static_cast<cl_uint>(products - 1),
             col_offsets_, columns_, constants_, light_, products_);
    if (wide_ids_) {
      set_args(phase2_, static_cast<cl_uint>(slices_), static_cast<cl_uint>(rows_),
               static_cast<float>(a.scale()), slice_offsets_, slice_rows_, slice_codes_, products_,
               out_);
    } else {
      set_args(phase2_, static_cast<cl_uint>(slices_), static_cast<cl_uint>(rows_),
               static_cast<float>(a.scale()), slice_offsets_, slice_rows_, slice_base_,
               slice_codes_, products_, out_);
    }
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "bicluster light");
    // Phase 1 always runs: it also writes the zero product of the last zero slot. The in-order
    // queue orders phase 2 after it.
    cl::Event e1 = launch(ctx_, "bicluster.phase1", phase1_, range1_);
    double ms = event_ms(ctx_, e1, "bicluster.phase1");
    if (slices_ > 0) {
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
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  ClContext& ctx_;
  std::size_t rows_, cols_, biclusters_, slices_;
  bool wide_ids_ = false;
  int dim_;
  std::size_t vertices_;
  std::vector<cl_float4> light_host_;
  cl::Kernel phase1_, phase2_;
  LaunchRange range1_, range2_;
  cl::Buffer col_offsets_, columns_, constants_, slice_offsets_, slice_rows_, slice_base_,
      slice_codes_, light_, products_, out_;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_arrays(ClContext& context, const BiclusterArrays& a,
                                               DeviceIds device_ids) {
  return std::make_unique<BiclusterDevice>(context, a, device_ids);
}

}  // namespace prt::bicluster
