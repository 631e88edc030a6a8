#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"
#include "svd/svd_material.h"

namespace prt::svd {
namespace {

class SvdDeviceMaterial final : public DeviceMaterial {
 public:
  SvdDeviceMaterial(ClContext& context, std::span<const SvdMaterial* const> parts)
      : mode_(parts.front()->mode()) {
    // Each distinct material once, in part order.
    std::map<const SvdMaterial*, cl_ulong2> placed;
    std::vector<float> a, b;
    std::vector<cl_int4> info;
    std::vector<cl_ulong2> bases;
    for (const SvdMaterial* p : parts) {
      const SvdState& s = p->state();
      auto it = placed.find(p);
      if (it == placed.end()) {
        const cl_ulong2 base{{static_cast<cl_ulong>(a.size()), static_cast<cl_ulong>(b.size())}};
        it = placed.emplace(p, base).first;
        if (mode_ == Mode::kAbrdf) {
          a.insert(a.end(), s.view_factors.begin(), s.view_factors.end());
          b.insert(b.end(), s.light_factors.begin(), s.light_factors.end());
        } else {
          a.insert(a.end(), s.coefficients.begin(), s.coefficients.end());
          b.insert(b.end(), s.mean.begin(), s.mean.end());
          b.insert(b.end(), s.components.begin(), s.components.end());
        }
      }
      bases.push_back(it->second);
      info.push_back(cl_int4{{s.sampling.resolution, s.sampling.view_side, s.rank, 0}});
      rank_ = std::max(rank_, s.rank);
    }
    m_ = parts.front()->sampling().light_count();
    a_ = upload(context, std::span<const float>(a), "svd material factors (a)");
    b_ = upload(context, std::span<const float>(b), "svd material factors (b)");
    info_ = upload(context, std::span<const cl_int4>(info), "svd part table");
    base_ = upload(context, std::span<const cl_ulong2>(bases), "svd part offsets");
    bytes_ = buffer_bytes({&a_, &b_, &info_, &base_});
    for (const SvdMaterial* p : parts) ranks_.push_back(p->rank());
  }

  std::string label() const override { return "svd.cl"; }
  std::string source() const override { return std::string(kernel_source("svd")); }
  KernelDefines defines() const override {
    return {{"SVD_PCA", mode_ == Mode::kTexelPca ? "1" : "0"}, {"SVD_RANK", std::to_string(rank_)}};
  }
  void set_args(cl::Kernel& kernel, unsigned first) const override {
    set_args_from(kernel, first, a_, b_, info_, base_);
  }
  std::uint64_t device_bytes() const override { return bytes_; }
  std::uint64_t bytes_per_hit(std::size_t part, TexelFilter filter) const override {
    const std::uint64_t texels = filter == TexelFilter::kBilinear ? 4 : 1;
    const auto k = static_cast<std::uint64_t>(ranks_.at(part));
    const auto m = static_cast<std::uint64_t>(m_);
    if (mode_ == Mode::kAbrdf) return texels * (4 * k * 3 + k * 3 * m) * sizeof(float);
    return (texels * k + 4 * (k + 1) * 3 * m) * sizeof(float);
  }

 private:
  Mode mode_;
  int rank_ = 1, m_ = 0;
  std::vector<int> ranks_;
  cl::Buffer a_, b_, info_, base_;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceMaterial> upload_svd(ClContext& context,
                                           std::span<const SvdMaterial* const> parts) {
  PRT_CHECK(!parts.empty(), "material svd: no parts to upload");
  for (const SvdMaterial* p : parts) {
    if (p->mode() != parts.front()->mode())
      throw ParameterError(fmt::format(
          "material svd: the parts mix modes {} and {}; one shading program evaluates one",
          mode_name(parts.front()->mode()), mode_name(p->mode())));
    if (p->sampling().light_count() != parts.front()->sampling().light_count())
      throw ParameterError("material svd: the parts differ in their light dimension");
  }
  return std::make_unique<SvdDeviceMaterial>(context, parts);
}

}  // namespace prt::svd
