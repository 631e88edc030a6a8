#pragma once
// Material backend `cmf`: chained matrix factorisation of every ABRDF of a BTF into
// P(d) Q(h) R(e), then normalisation, clustering and 8-bit quantisation (Suykens et al. 2003;
// README.md). The factored representation and its shading are core's FactoredMaterial.
#include <string_view>

#include "cmf/chained_factorization.h"
#include "prtlab/compress/material_registry.h"

namespace prt::cmf {

inline constexpr std::string_view kName = "cmf";

MaterialEntry registry_entry();

}  // namespace prt::cmf
