// Material backend `svd`: its compressor and registry entry (README.md).
#include <fmt/format.h>

#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/compress/material_registry.h"
#include "svd/abrdf_truncation.h"
#include "svd/svd_material.h"
#include "svd/texel_pca.h"

namespace prt::svd {
namespace {

class SvdCompressor final : public MaterialCompressor {
 public:
  SvdCompressor(Mode mode, int rank, nlohmann::json parameters)
      : mode_(mode), rank_(rank), parameters_(std::move(parameters)) {}
  std::unique_ptr<CompressedMaterial> compress(const MaterialInput& input,
                                               Progress& progress) const override {
    if (!input.btf) throw ParameterError("material svd: no BTF given");
    const Btf& btf = *input.btf;
    for (std::size_t i = 0; i < btf.value_count(); ++i)
      if (!std::isfinite(btf.data()[i]))
        throw ParameterError(
            fmt::format("material svd: BTF '{}' holds the non-finite value {} "
                        "at index {}",
                        btf.material(), btf.data()[i], i));
    SvdState s = mode_ == Mode::kAbrdf ? truncate_abrdfs(btf, rank_) : texel_pca(btf, rank_);
    s.parameters = parameters_;
    progress.finish();
    return std::make_unique<SvdMaterial>(std::move(s));
  }

 private:
  Mode mode_;
  int rank_;
  nlohmann::json parameters_;
};

MaterialEntry registry_entry() {
  MaterialEntry e;
  e.name = std::string(kName);
  e.description =
      "baselines at equal storage for the BTF factorisations: each ABRDF (per texel and channel) "
      "truncated to rank K by its SVD, or a PCA of the texels' ABRDFs with K shared components; "
      "float32";
  e.params = {
      {"mode",
       ParamType::kEnum,
       "abrdf",
       {},
       {},
       {"abrdf", "texel_pca"},
       "abrdf: every V x M ABRDF matrix per texel and channel truncated to rank K, K (V + M) "
       "floats per texel and channel; texel_pca: mean + K principal components of the texels' "
       "3 M V-value ABRDFs, shared, and K coefficients per texel"},
      {"rank",
       ParamType::kInt,
       "1",
       1,
       4096,
       {},
       "K, the size knob (storage grows with it): at most min(V, M) for abrdf, min(U^2, 3 M V) "
       "for texel_pca"}};
  e.lossless = false;
  e.create = [](const ParamSet& p) -> std::unique_ptr<MaterialCompressor> {
    return std::make_unique<SvdCompressor>(mode_from(p.get_string("mode")),
                                           static_cast<int>(p.get_int("rank")),
                                           nlohmann::json(p.canonical()));
  };
  e.load = &SvdMaterial::load;
  return e;
}

PRT_REGISTER_MATERIAL(registry_entry);

}  // namespace
}  // namespace prt::svd
