// The OpenCL relight of backend `uncompressed` (compressors/uncompressed/uncompressed.cl).
#include <bit>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/sphere/lit_faces.h"
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
  UncompressedDevice(ClContext& ctx, const TransferMatrix& t, const Options& options,
                     const FaceTable* faces)
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
    if (!lanes) {
      // The culled kernels sum like uncompressed_rows (bit-identical rows); the lanes variant's
      // reduction has no such twin, so it relights every row of every light.
      culled_ = true;
      has_faces_ = options.skip_faces && faces != nullptr && !faces->empty();
      face_starts_ = has_faces_ ? upload(ctx, faces->starts(), "uncompressed face starts")
                                : make_buffer(ctx, 0, CL_MEM_READ_ONLY, "uncompressed face starts");
      rows_faces_ = make_kernel(program, "uncompressed_rows_faces");
      vertices_kernel_ = make_kernel(program, "uncompressed_vertices");
    }
    bytes_ = buffer_bytes({&offsets_, &columns_, &counts_, &light_, &out_, &face_starts_});
    set_args(kernel_, static_cast<cl_uint>(rows_), scale_, offsets_, columns_, counts_, light_,
             out_);
  }

  bool supports_vertex_subset() const override { return culled_; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    if (!culled_) return;
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    if (!culled_) return relight_on_device(light);
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "uncompressed light");
    const std::size_t subset_rows = subset_.size() * static_cast<std::size_t>(dim_);
    if (subset_rows == 0) return 0.0;
    set_args(vertices_kernel_, static_cast<cl_uint>(subset_rows), static_cast<cl_uint>(dim_),
             subset_.buffer(), scale_, offsets_, columns_, counts_, face_starts_, lit_of(light),
             light_, out_);
    cl::Event event = launch(ctx_, "uncompressed.vertices", vertices_kernel_,
                             LaunchRange::linear(subset_rows, kRowsWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name,
                              "timing of kernel uncompressed.vertices");
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "uncompressed light");
    if (rows_ == 0) return 0.0;  // OpenCL forbids an empty launch
    const cl_uint lit = culled_ ? lit_of(light) : kAllFaces;
    if (lit != kAllFaces) {
      set_args(rows_faces_, static_cast<cl_uint>(rows_), scale_, offsets_, columns_, counts_,
               face_starts_, lit, light_, out_);
      cl::Event event = launch(ctx_, "uncompressed.rows_faces", rows_faces_, range_);
      return event_milliseconds(event, ctx_.info().device_name,
                                "timing of kernel uncompressed.rows_faces");
    }
    cl::Event event = launch(ctx_, launch_name_, kernel_, range_);
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel " + launch_name_);
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, dim_, vertices_);
    download(ctx_, out_, std::span<Rgb>(out.values), "uncompressed local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  // The faces of `light` the kernels sum over (every face without a face table).
  cl_uint lit_of(const LightCoeffs& light) const {
    return has_faces_ ? lit_faces(light.values) : kAllFaces;
  }

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
  // Culling (rows variant only): the face table, the kernels, the vertex subset.
  bool culled_ = false, has_faces_ = false;
  cl::Buffer face_starts_;
  cl::Kernel rows_faces_, vertices_kernel_;
  DeviceIdList subset_{"uncompressed vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_transfer(ClContext& context, const TransferMatrix& transfer,
                                                 const Options& options, const FaceTable* faces) {
  return std::make_unique<UncompressedDevice>(context, transfer, options, faces);
}

}  // namespace prt::uncompressed
