#pragma once
// Material backend `hf`: homomorphic factorisation of every ABRDF of a BTF into P(d) Q(h) R(e)
// (McCool et al. 2001, the baseline of Suykens et al. 2003), then the same normalisation,
// clustering and 8-bit quantisation as `cmf` (core's FactoredMaterial; README.md).
#include <string_view>

#include "hf/homomorphic_factorization.h"
#include "prtlab/compress/material_registry.h"

namespace prt::hf {

inline constexpr std::string_view kName = "hf";

MaterialEntry registry_entry();

}  // namespace prt::hf
