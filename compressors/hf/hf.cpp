#include "hf/hf.h"

#include "prtlab/base/error.h"
#include "prtlab/render/factored_material.h"

namespace prt::hf {

MaterialEntry registry_entry() {
  MaterialEntry e;
  e.name = std::string(kName);
  e.description =
      "homomorphic factorisation (McCool et al. 2001, as Suykens et al. 2003 compare it): each "
      "ABRDF as P(light) Q(halfway) R(view) by least squares in logarithms with a Laplacian "
      "regulariser, then clustered and 8-bit like cmf";
  e.params = {
      {"lambda",
       ParamType::kReal,
       "0.1",
       1e-4,
       1e3,
       {},
       "weight of the Laplacian smoothness rows of each factor (the paper's lambda); halfway "
       "cells no sample reaches are held by these rows alone, so very small values are "
       "ill-conditioned"},
      {"floor",
       ParamType::kReal,
       "0.001",
       1e-12,
       0.5,
       {},
       "samples below floor x the ABRDF channel's maximum are raised to it before the "
       "logarithm (shadowed zeros have none)"},
      {"refine",
       ParamType::kInt,
       "0",
       0,
       100,
       {},
       "Gauss-Newton iterations after the log fit on the same model in linear terms (squared "
       "error of the product plus the same regulariser; not in the paper, whose fit is the log "
       "one: 0)"}};
  for (auto& spec : factor_coding_params()) e.params.push_back(std::move(spec));
  e.lossless = false;
  e.create = [](const ParamSet& p) -> std::unique_ptr<MaterialCompressor> {
    HomomorphicOptions o;
    o.half_side = static_cast<int>(p.get_int("half_side"));
    o.lambda = p.get_real("lambda");
    o.floor = p.get_real("floor");
    o.refine = static_cast<int>(p.get_int("refine"));
    const auto setup = [o](const Btf& btf) -> ChannelFactorizer {
      HomomorphicOptions with = o;
      with.light_side = btf.light_side();
      with.view_side = btf.view_side();
      return channel_factorizer(std::make_shared<const HomomorphicFactorization>(with));
    };
    // The log fit's model interpolates log Q between halfway cells: shading must do the same.
    FactorCoding coding = factor_coding(p);
    coding.interpolation = HalfwayInterpolation::kGeometric;
    return std::make_unique<FactoredCompressor>(std::string(kName), setup, coding,
                                                nlohmann::json(p.canonical()));
  };
  e.load = factored_loader(std::string(kName));
  return e;
}

PRT_REGISTER_MATERIAL(registry_entry);

}  // namespace prt::hf
