// The OpenCL relight of backend `srbf_cta` (compressors/srbf_cta/srbf_cta.cl).
#include <fmt/format.h>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"
#include "srbf_cta/srbf_cta.h"

namespace prt::srbf_cta {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

constexpr std::size_t kWorkGroup = 64;

cl::Buffer upload_or_dummy(ClContext& ctx, const std::vector<float>& v, const char* what) {
  static const float kDummy[1] = {0.f};
  return v.empty() ? upload(ctx, std::span<const float>(kDummy), what)
                   : upload(ctx, std::span<const float>(v), what);
}

class SrbfCtaDevice final : public DeviceRelighter {
 public:
  SrbfCtaDevice(ClContext& ctx, const SrbfCtaArrays& a, std::string light_basis)
      : ctx_(ctx),
        vertices_(a.vertices),
        clusters_(a.clusters()),
        nt_(static_cast<std::size_t>(a.srbf_count)),
        m_(static_cast<std::size_t>(a.local_count)),
        r1_(static_cast<std::size_t>(a.rank_view)),
        r2_(static_cast<std::size_t>(a.rank_light)),
        r3_(static_cast<std::size_t>(a.rank_vertex)),
        light_basis_(std::move(light_basis)),
        light_host_(nt_) {
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup);
    const cl::Program program = build_program(ctx, "srbf_cta", defines);
    k_light_ = make_kernel(program, "srbf_cta_light");
    k_cores_ = make_kernel(program, "srbf_cta_cores");
    k_expand_ = make_kernel(program, "srbf_cta_expand");
    k_vertices_ = make_kernel(program, "srbf_cta_vertices");
    k_subset_ = make_kernel(program, "srbf_cta_vertices_subset");
    view_ = upload_or_dummy(ctx, a.view_basis, "srbf_cta view basis");
    light_bases_ = upload_or_dummy(ctx, a.light_bases, "srbf_cta light bases");
    duals_ = upload_or_dummy(ctx, a.duals, "srbf_cta dual bases");
    weights_ = upload_or_dummy(ctx, a.weights, "srbf_cta weights");
    ids_ = upload(ctx, std::span<const std::uint32_t>(a.ids), "srbf_cta cluster ids");
    light_ = make_buffer(ctx, nt_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "srbf_cta light");
    lc_ = make_buffer(ctx, std::max<std::size_t>(1, clusters_ * r2_) * sizeof(cl_float4),
                      CL_MEM_READ_WRITE, "srbf_cta cluster light");
    cores_ = make_buffer(ctx, std::max<std::size_t>(1, clusters_ * r1_ * r3_) * sizeof(cl_float4),
                         CL_MEM_READ_WRITE, "srbf_cta cluster cores");
    q_ = make_buffer(ctx, std::max<std::size_t>(1, clusters_ * m_ * r3_) * sizeof(cl_float4),
                     CL_MEM_READ_WRITE, "srbf_cta cluster matrices");
    out_ = make_buffer(ctx, std::max<std::size_t>(1, vertices_ * m_) * sizeof(Rgb),
                       CL_MEM_READ_WRITE, "srbf_cta local radiance");
    set_args(k_light_, static_cast<cl_uint>(clusters_ * r2_), static_cast<cl_uint>(nt_),
             static_cast<cl_uint>(r2_), light_bases_, light_, lc_);
    set_args(k_cores_, static_cast<cl_uint>(clusters_ * r1_ * r3_), static_cast<cl_uint>(r1_),
             static_cast<cl_uint>(r2_), static_cast<cl_uint>(r3_), duals_, lc_, cores_);
    set_args(k_expand_, static_cast<cl_uint>(clusters_ * m_ * r3_), static_cast<cl_uint>(m_),
             static_cast<cl_uint>(r1_), static_cast<cl_uint>(r3_), view_, cores_, q_);
    set_args(k_vertices_, static_cast<cl_uint>(vertices_ * m_), static_cast<cl_uint>(m_),
             static_cast<cl_uint>(r3_), ids_, weights_, q_, out_);
    bytes_ = buffer_bytes(
        {&view_, &light_bases_, &duals_, &weights_, &ids_, &light_, &lc_, &cores_, &q_, &out_});
  }

  bool supports_vertex_subset() const override { return true; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, vertices_, kName);
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    double ms = clusters_step(light);
    const std::size_t items = subset_.size() * m_;
    if (items == 0) return ms;
    set_args(k_subset_, static_cast<cl_uint>(items), static_cast<cl_uint>(m_),
             static_cast<cl_uint>(r3_), subset_.buffer(), ids_, weights_, q_, out_);
    ms += timed("srbf_cta.vertices_subset", k_subset_, items);
    return ms;
  }

  double relight_on_device(const LightCoeffs& light) override {
    double ms = clusters_step(light);
    if (vertices_ * m_ > 0) ms += timed("srbf_cta.vertices", k_vertices_, vertices_ * m_);
    return ms;
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, static_cast<int>(m_), vertices_);
    if (!out.values.empty())
      download(ctx_, out_, std::span<Rgb>(out.values), "srbf_cta local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  double timed(const char* name, cl::Kernel& k, std::size_t items) {
    cl::Event e = launch(ctx_, name, k, LaunchRange::linear(items, kWorkGroup));
    return event_milliseconds(e, ctx_.info().device_name, fmt::format("timing of kernel {}", name));
  }

  /// The light upload and the three per-cluster launches.
  double clusters_step(const LightCoeffs& light) {
    if (light.basis != light_basis_ || light.values.size() != nt_)
      throw ParameterError(fmt::format(
          "{}: the light is in basis '{}' with {} values, the transfer needs '{}' with {}", kName,
          light.basis, light.values.size(), light_basis_, nt_));
    upload_light(ctx_, light_, light.values, light_host_, "srbf_cta light");
    if (clusters_ == 0) return 0.0;
    double ms = timed("srbf_cta.light", k_light_, clusters_ * r2_);
    ms += timed("srbf_cta.cores", k_cores_, clusters_ * r1_ * r3_);
    ms += timed("srbf_cta.expand", k_expand_, clusters_ * m_ * r3_);
    return ms;
  }

  ClContext& ctx_;
  std::size_t vertices_, clusters_, nt_, m_, r1_, r2_, r3_;
  std::string light_basis_;
  std::vector<cl_float4> light_host_;
  cl::Kernel k_light_, k_cores_, k_expand_, k_vertices_, k_subset_;
  cl::Buffer view_, light_bases_, duals_, weights_, ids_, light_, lc_, cores_, q_, out_;
  std::uint64_t bytes_ = 0;
  DeviceIdList subset_{"srbf_cta vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_srbf_cta(ClContext& context, const SrbfCtaArrays& arrays,
                                                 const std::string& light_basis) {
  return std::make_unique<SrbfCtaDevice>(context, arrays, light_basis);
}

}  // namespace prt::srbf_cta
