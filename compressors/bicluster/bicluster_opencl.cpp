// The OpenCL relight of backend `bicluster` (compressors/bicluster/bicluster.cl): two launches per
// relight, phase 1 a work-item per bicluster (plus one for the last zero slot's product), phase 2 a
// work-item per slice of 4 rows.
#include <limits>

#include "bicluster/bicluster.h"
#include "bicluster/bicluster_culling.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/sphere/lit_faces.h"

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
  BiclusterDevice(ClContext& ctx, const BiclusterArrays& a, DeviceIds device_ids, bool skip_faces)
      : ctx_(ctx),
        rows_(a.rows()),
        cols_(static_cast<std::size_t>(a.pixel_count)),
        biclusters_(a.bicluster_count()),
        slices_(a.slice_count()),
        dim_(a.local_count),
        vertices_(a.vertices),
        skip_faces_(skip_faces),
        scale_(static_cast<float>(a.scale())),
        light_host_(cols_),
        row_lanes_(row_lanes(a)) {
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
    phase2_subset_ =
        make_kernel(program, wide_ids_ ? "bicluster_phase2_ids_subset" : "bicluster_phase2_subset");
    range1_ = LaunchRange::linear(biclusters_ / kPhase1PerItem + 1, kWorkGroup);
    const std::size_t products = a.product_count();
    range2_ = LaunchRange::linear(slices_, kWorkGroup);

    col_offsets_ = upload_nonempty(ctx, a.bic_col_offsets, "bicluster column offsets");
    columns_ = upload_columns(ctx, a.bic_columns, narrow, "bicluster columns");
    constants_ = upload_nonempty(ctx, a.bic_constants, "bicluster constants");
    faces_ = upload_nonempty(ctx, bicluster_faces(a), "bicluster faces");
    subset_ = make_buffer(ctx, 0, CL_MEM_READ_ONLY, "bicluster slice subset");
    subset_lanes_ = make_buffer(ctx, 0, CL_MEM_READ_ONLY, "bicluster subset lanes");
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
    bytes_ = buffer_bytes({&col_offsets_, &columns_, &constants_, &faces_, &slice_offsets_,
                           &slice_rows_, &slice_base_, &slice_codes_, &light_, &products_, &out_});
    set_args(phase1_, static_cast<cl_uint>(biclusters_), static_cast<cl_uint>(products - 1),
             col_offsets_, columns_, constants_, faces_, cl_uint{kAllFaces}, light_, products_);
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

  bool supports_vertex_subset() const override { return true; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    const SliceSubset subset = slices_of(slices_, dim_, row_lanes_, vertices);
    subset_count_ = subset.slices.size();
    if (subset_count_ > subset_capacity_) {
      subset_capacity_ = subset_count_;
      subset_ = make_buffer(ctx_, subset_capacity_ * sizeof(std::uint32_t), CL_MEM_READ_ONLY,
                            "bicluster slice subset");
      subset_lanes_ =
          make_buffer(ctx_, subset_capacity_, CL_MEM_READ_ONLY, "bicluster subset lanes");
    }
    if (subset_count_ == 0) return;
    write_buffer(ctx_, subset_, subset.slices.data(), subset_count_ * sizeof(std::uint32_t),
                 "bicluster slice subset");
    write_buffer(ctx_, subset_lanes_, subset.lanes.data(), subset_count_, "bicluster subset lanes");
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    double ms = run_phase1(light);
    if (subset_count_ > 0) {
      if (wide_ids_) {
        set_args(phase2_subset_, static_cast<cl_uint>(subset_count_), subset_, subset_lanes_,
                 static_cast<cl_uint>(rows_), scale_, slice_offsets_, slice_rows_, slice_codes_,
                 products_, out_);
      } else {
        set_args(phase2_subset_, static_cast<cl_uint>(subset_count_), subset_, subset_lanes_,
                 static_cast<cl_uint>(rows_), scale_, slice_offsets_, slice_rows_, slice_base_,
                 slice_codes_, products_, out_);
      }
      cl::Event e2 = launch(ctx_, "bicluster.phase2_subset", phase2_subset_,
                            LaunchRange::linear(subset_count_, kWorkGroup));
      ms += event_ms(ctx_, e2, "bicluster.phase2_subset");
    }
    return ms;
  }

  double relight_on_device(const LightCoeffs& light) override {
    double ms = run_phase1(light);
    if (slices_ > 0) {
      cl::Event e2 = launch(ctx_, "bicluster.phase2", phase2_, range2_);
      ms += event_ms(ctx_, e2, "bicluster.phase2");
    }
    return ms;
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, dim_, vertices_);
    if (rows_ > 0) download(ctx_, out_, std::span<Rgb>(out.values), "bicluster local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }

 private:
  // Uploads the light and runs phase 1; phase 2 follows on the in-order queue.
  double run_phase1(const LightCoeffs& light) {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "bicluster light");
    // Phase 1 always runs: it also writes the zero product of the last zero slot.
    set_args_from(phase1_, 6, cl_uint{skip_faces_ ? lit_faces(light.values) : kAllFaces});
    cl::Event e1 = launch(ctx_, "bicluster.phase1", phase1_, range1_);
    return event_ms(ctx_, e1, "bicluster.phase1");
  }

 public:
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  ClContext& ctx_;
  std::size_t rows_, cols_, biclusters_, slices_;
  bool wide_ids_ = false;
  int dim_;
  std::size_t vertices_;
  bool skip_faces_;
  float scale_;
  std::vector<cl_float4> light_host_;
  // Vertex subsets: each row's lane, the subset's slices and lanes on the device.
  std::vector<std::uint32_t> row_lanes_;
  std::size_t subset_count_ = 0, subset_capacity_ = 0;
  cl::Buffer faces_, subset_, subset_lanes_;
  cl::Kernel phase1_, phase2_, phase2_subset_;
  LaunchRange range1_, range2_;
  cl::Buffer col_offsets_, columns_, constants_, slice_offsets_, slice_rows_, slice_base_,
      slice_codes_, light_, products_, out_;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_arrays(ClContext& context, const BiclusterArrays& a,
                                               DeviceIds device_ids, bool skip_faces) {
  return std::make_unique<BiclusterDevice>(context, a, device_ids, skip_faces);
}

}  // namespace prt::bicluster
