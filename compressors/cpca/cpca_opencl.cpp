// The OpenCL relight of backend `cpca` (compressors/cpca/cpca.cl).
#include <limits>

#include "cpca/cpca.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::cpca {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

constexpr std::size_t kWorkGroup = 64;

std::string_view id_type(std::size_t bytes) {
  return bytes == 1 ? "uchar" : (bytes == 2 ? "ushort" : "uint");
}

int weight_format_code(WeightFormat f) {
  return f == WeightFormat::kFloat32 ? 0 : (f == WeightFormat::kFloat16 ? 1 : 2);
}

class CpcaDevice final : public DeviceRelighter {
 public:
  CpcaDevice(ClContext& ctx, const CpcaArrays& a)
      : ctx_(ctx),
        rows_(a.rows()),
        reps_(a.rep_count()),
        cols_(static_cast<std::size_t>(a.pixel_count)),
        dim_(a.local_count),
        terms_(a.view_terms),
        vertices_(a.vertices),
        light_host_(cols_) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max() ||
        reps_ * cols_ > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(
          fmt::format("{}: {} rows or {} representatives exceed the kernels' u32 "
                      "indices",
                      kName, rows_, reps_));
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_ID_T", id_type(a.id_bytes()))
        .set("PRT_WEIGHT_FORMAT", weight_format_code(a.format));
    const cl::Program program = build_program(ctx, "cpca", defines);
    dots_ = make_kernel(program, "cpca_dots");
    blend_ = make_kernel(program, "cpca_blend");
    blend_vertices_ = make_kernel(program, "cpca_blend_vertices");
    view_ = make_kernel(program, "cpca_view");

    switch (a.id_bytes()) {
      case 1: {
        const std::vector<std::uint8_t> ids(a.ids.begin(), a.ids.end());
        ids_ = upload(ctx, std::span<const std::uint8_t>(ids), "cpca cluster ids");
        break;
      }
      case 2: {
        const std::vector<std::uint16_t> ids(a.ids.begin(), a.ids.end());
        ids_ = upload(ctx, std::span<const std::uint16_t>(ids), "cpca cluster ids");
        break;
      }
      default:
        ids_ = upload(ctx, std::span<const std::uint32_t>(a.ids), "cpca cluster ids");
    }
    first_ = upload(ctx, std::span<const std::uint32_t>(a.first), "cpca representative offsets");
    offsets_ =
        upload(ctx, std::span<const std::uint32_t>(a.weight_offsets), "cpca row weight offsets");
    // A zero-length buffer is not allowed: empty weight arrays get one dummy element.
    static const float kDummy[1] = {0.f};
    static const std::uint16_t kDummyHalf[1] = {0};
    static const std::int8_t kDummyCode[1] = {0};
    switch (a.format) {
      case WeightFormat::kFloat32:
        weights_ = a.weights32.empty()
                       ? upload(ctx, std::span<const float>(kDummy), "cpca weights")
                       : upload(ctx, std::span<const float>(a.weights32), "cpca weights");
        break;
      case WeightFormat::kFloat16:
        weights_ = a.weights16.empty()
                       ? upload(ctx, std::span<const std::uint16_t>(kDummyHalf), "cpca weights")
                       : upload(ctx, std::span<const std::uint16_t>(a.weights16), "cpca weights");
        break;
      case WeightFormat::kS8:
        weights_ = a.codes.empty()
                       ? upload(ctx, std::span<const std::int8_t>(kDummyCode), "cpca weights")
                       : upload(ctx, std::span<const std::int8_t>(a.codes), "cpca weights");
        break;
    }
    scales_ = a.row_scales.empty()
                  ? upload(ctx, std::span<const float>(kDummy), "cpca row scales")
                  : upload(ctx, std::span<const float>(a.row_scales), "cpca row scales");
    representatives_ = upload(ctx, std::span<const float>(a.reps), "cpca representatives");
    products_ = make_buffer(ctx, reps_ * sizeof(cl_float4), CL_MEM_READ_WRITE, "cpca products");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "cpca light");
    outputs_ = vertices_ * static_cast<std::size_t>(dim_);
    out_ = make_buffer(ctx, outputs_ * sizeof(Rgb), CL_MEM_READ_WRITE, "cpca local radiance");
    set_args(dots_, static_cast<cl_uint>(reps_), static_cast<cl_uint>(cols_), representatives_,
             light_, products_);
    if (terms_ > 0) {
      // The BRDF signal: the rows blend into the K terms of each vertex, which Phi maps to the
      // output.
      if (outputs_ > std::numeric_limits<std::uint32_t>::max())
        throw ParameterError(
            fmt::format("{}: {} outputs exceed the kernels' u32 indices", kName, outputs_));
      view_buffer_ = upload(ctx, std::span<const float>(a.view), "cpca view factor");
      terms_buffer_ = make_buffer(ctx, rows_ * sizeof(Rgb), CL_MEM_READ_WRITE, "cpca BRDF terms");
      set_args(blend_, static_cast<cl_uint>(rows_), ids_, first_, offsets_, weights_, scales_,
               products_, terms_buffer_);
      set_args(view_, static_cast<cl_uint>(outputs_), static_cast<cl_uint>(dim_),
               static_cast<cl_uint>(terms_), view_buffer_, terms_buffer_, out_);
    } else {
      set_args(blend_, static_cast<cl_uint>(rows_), ids_, first_, offsets_, weights_, scales_,
               products_, out_);
    }
    bytes_ = buffer_bytes({&ids_, &first_, &offsets_, &weights_, &scales_, &representatives_,
                           &products_, &light_, &out_});
    if (terms_ > 0) bytes_ += buffer_bytes({&view_buffer_, &terms_buffer_});
  }

  bool supports_vertex_subset() const override { return terms_ == 0; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    if (terms_ > 0) return relight_on_device(light);
    const double ms = products(light);
    const std::size_t subset_rows = subset_.size() * static_cast<std::size_t>(dim_);
    if (subset_rows == 0) return ms;
    set_args(blend_vertices_, static_cast<cl_uint>(subset_rows), static_cast<cl_uint>(dim_),
             subset_.buffer(), ids_, first_, offsets_, weights_, scales_, products_, out_);
    cl::Event event = launch(ctx_, "cpca.blend_vertices", blend_vertices_,
                             LaunchRange::linear(subset_rows, kWorkGroup));
    return ms + event_milliseconds(event, ctx_.info().device_name,
                                   "timing of kernel cpca.blend_vertices");
  }

  double relight_on_device(const LightCoeffs& light) override {
    const double ms = products(light);
    if (rows_ == 0) return ms;
    cl::Event event = launch(ctx_, "cpca.blend", blend_, LaunchRange::linear(rows_, kWorkGroup));
    double total =
        ms + event_milliseconds(event, ctx_.info().device_name, "timing of kernel cpca.blend");
    if (terms_ > 0) {
      cl::Event view = launch(ctx_, "cpca.view", view_, LaunchRange::linear(outputs_, kWorkGroup));
      total += event_milliseconds(view, ctx_.info().device_name, "timing of kernel cpca.view");
    }
    return total;
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, dim_, vertices_);
    download(ctx_, out_, std::span<Rgb>(out.values), "cpca local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  // Uploads the light and launches the per-representative products; returns kernel ms.
  double products(const LightCoeffs& light) {
    check_pixel_light(light, cols_, kName);
    upload_light(ctx_, light_, light.values, light_host_, "cpca light");
    if (reps_ == 0) return 0.0;
    cl::Event event =
        launch(ctx_, "cpca.dots", dots_, LaunchRange::linear(reps_ * kWorkGroup, kWorkGroup));
    return event_milliseconds(event, ctx_.info().device_name, "timing of kernel cpca.dots");
  }

  ClContext& ctx_;
  std::size_t rows_, reps_, cols_;
  int dim_;
  int terms_;
  std::size_t vertices_;
  std::size_t outputs_ = 0;
  std::vector<cl_float4> light_host_;
  cl::Kernel dots_, blend_, blend_vertices_, view_;
  cl::Buffer ids_, first_, offsets_, weights_, scales_, representatives_, products_, light_, out_;
  cl::Buffer view_buffer_, terms_buffer_;
  std::uint64_t bytes_ = 0;
  DeviceIdList subset_{"cpca vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_cpca(ClContext& context, const CpcaArrays& arrays) {
  return std::make_unique<CpcaDevice>(context, arrays);
}

}  // namespace prt::cpca
