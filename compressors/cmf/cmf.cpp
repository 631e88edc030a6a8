#include "cmf/cmf.h"

#include "prtlab/base/error.h"
#include "prtlab/render/factored_material.h"

namespace prt::cmf {

MaterialEntry registry_entry() {
  MaterialEntry e;
  e.name = std::string(kName);
  e.description =
      "chained matrix factorisation (Suykens et al. 2003): each ABRDF as P(light) Q(halfway) "
      "R(view), clustered codebooks with index and scale maps, 8-bit factors";
  e.params = {
      {"diff_side",
       ParamType::kInt,
       "8",
       0,
       64,
       {},
       "side of the GSHD difference grid of the resampling step; 0: half_side"},
      {"halfway",
       ParamType::kEnum,
       "svd",
       0,
       0,
       {"svd", "mean", "project"},
       "halfway factor: the rank-1 SVD of the GSHD matrix over its valid entries with the "
       "difference factor averaged out (the paper's four-factor step reduced to three), the "
       "mean of each halfway row (the paper's three-factor rule), or the samples projected "
       "onto the halfway grid without resampling (not in the paper)"},
      {"refine",
       ParamType::kInt,
       "10",
       0,
       2000,
       {},
       "alternating least-squares sweeps on P Q R in the original samples after the chain "
       "(not in the paper; refine = 0 with halfway = mean is the paper's chain)"},
      {"terms",
       ParamType::kInt,
       "1",
       1,
       kMaxFactorTerms,
       {},
       "P R terms per ABRDF channel after the halfway factor (the paper's multiple-term "
       "approximation, eq. 3), non-negative so that they stay 8-bit textures: each adds a P and "
       "an R index and a scale per texel; 1 is the paper's single term"}};
  for (auto& spec : factor_coding_params()) e.params.push_back(std::move(spec));
  e.lossless = false;
  e.create = [](const ParamSet& p) -> std::unique_ptr<MaterialCompressor> {
    ChainOptions o;
    o.half_side = static_cast<int>(p.get_int("half_side"));
    o.diff_side = static_cast<int>(p.get_int("diff_side"));
    const std::string& rule = p.get_string("halfway");
    o.halfway = rule == "mean"      ? HalfwayRule::kMean
                : rule == "project" ? HalfwayRule::kProject
                                    : HalfwayRule::kSvd;
    o.refine = static_cast<int>(p.get_int("refine"));
    o.terms = static_cast<int>(p.get_int("terms"));
    FactorCoding coding = factor_coding(p);
    coding.terms = o.terms;
    const auto setup = [o](const Btf& btf) -> ChannelFactorizer {
      ChainOptions with = o;
      with.light_side = btf.light_side();
      with.view_side = btf.view_side();
      if (with.diff_side == 0) with.diff_side = with.half_side;
      return channel_factorizer(std::make_shared<const ChainedFactorization>(with));
    };
    return std::make_unique<FactoredCompressor>(std::string(kName), setup, coding,
                                                nlohmann::json(p.canonical()));
  };
  e.load = factored_loader(std::string(kName));
  return e;
}

PRT_REGISTER_MATERIAL(registry_entry);

}  // namespace prt::cmf
