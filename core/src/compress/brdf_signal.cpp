#include "prtlab/compress/brdf_signal.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <utility>

#include "prtlab/base/error.h"
#include "prtlab/base/progress.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

std::string BrdfSignalParams::key() const {
  if (!enabled) return "cells";
  return fmt::format("kd={} m={} F0={} K={}", brdf.diffuse, brdf.roughness, brdf.fresnel0, terms);
}

std::span<const ParamSpec> brdf_signal_param_specs() {
  static const std::vector<ParamSpec> specs = {
      {"signal",
       ParamType::kEnum,
       "cells",
       std::nullopt,
       std::nullopt,
       {"cells", "brdf"},
       "the signal compressed: T's M local cells (relight: local radiance), or the BRDF-weighted "
       "transfer of Tsai and Shih 2006 in brdf_terms Cook-Torrance terms (relight: outgoing "
       "radiance towards the cells)"},
      {"brdf_terms",
       ParamType::kInt,
       "16",
       1.0,
       4096.0,
       {},
       "K, separable BRDF terms of the brdf signal (the paper: 16; at most M)"},
      {"brdf_diffuse",
       ParamType::kReal,
       "0.3",
       0.0,
       1.0,
       {},
       "Cook-Torrance kd, the Lambertian share of the brdf signal's BRDF"},
      {"brdf_roughness",
       ParamType::kReal,
       "0.3",
       0.01,
       10.0,
       {},
       "Cook-Torrance Beckmann roughness m of the brdf signal's BRDF"},
      {"brdf_fresnel0",
       ParamType::kReal,
       "0.5",
       0.0,
       1.0,
       {},
       "Cook-Torrance Schlick F0 of the brdf signal's BRDF"},
  };
  return specs;
}

BrdfSignalParams brdf_signal_params(const ParamSet& ps) {
  BrdfSignalParams p;
  p.enabled = ps.get_enum<bool>("signal", {{"cells", false}, {"brdf", true}});
  p.terms = static_cast<int>(ps.get_int("brdf_terms"));
  p.brdf.diffuse = ps.get_real("brdf_diffuse");
  p.brdf.roughness = ps.get_real("brdf_roughness");
  p.brdf.fresnel0 = ps.get_real("brdf_fresnel0");
  p.brdf.validate();
  return p;
}

RowSet FoldedRows::row_set() const {
  if (pixels <= 65536)
    return RowSet::csr(pixels, offsets, std::span<const std::uint16_t>(columns16),
                       std::span<const float>(values));
  return RowSet::csr(pixels, offsets, std::span<const std::uint32_t>(columns32),
                     std::span<const float>(values));
}

std::uint64_t FoldedRows::memory_bytes() const {
  return offsets.size() * std::uint64_t{4} + columns16.size() * std::uint64_t{2} +
         columns32.size() * std::uint64_t{4} + values.size() * std::uint64_t{4};
}

FoldedRows fold_transfer_rows(const TransferMatrix& t, const HemisphereGrid& grid,
                              const BrdfSignalParams& params, Progress& progress) {
  const int m = t.local_count();
  if (m != grid.cell_count())
    throw ParameterError(
        fmt::format("BRDF signal: a transfer of {} local cells for a hemisphere grid of {}", m,
                    grid.cell_count()));
  FoldedRows out;
  out.fold = fold_brdf(grid, params.brdf, params.terms);
  out.vertices = t.vertex_count();
  out.pixels = t.cols();
  const auto k = static_cast<std::size_t>(params.terms);
  const auto mm = static_cast<std::size_t>(m);

  // Pass 1: the distinct pixels of every vertex block (T_x's columns), which every one of its
  // K folded rows holds.
  std::vector<std::uint32_t> distinct(out.vertices);
  std::vector<std::vector<std::uint32_t>> columns(out.vertices);
  tbb::parallel_for(std::size_t{0}, out.vertices, [&](std::size_t x) {
    std::vector<std::uint32_t>& c = columns[x];
    const auto offsets = t.row_offsets();
    for (std::size_t row = x * mm; row < (x + 1) * mm; ++row)
      for (std::uint32_t e = offsets[row]; e < offsets[row + 1]; ++e) c.push_back(t.column(e));
    std::sort(c.begin(), c.end());
    c.erase(std::unique(c.begin(), c.end()), c.end());
    distinct[x] = static_cast<std::uint32_t>(c.size());
  });
  std::vector<std::uint64_t> starts(out.vertices + 1, 0);
  for (std::size_t x = 0; x < out.vertices; ++x) starts[x + 1] = starts[x] + distinct[x] * k;
  if (starts.back() > std::numeric_limits<std::uint32_t>::max())
    throw ParameterError(fmt::format(
        "BRDF signal: {} folded values ({} terms of {} vertices) overflow the u32 row offsets",
        starts.back(), k, out.vertices));
  out.offsets.resize(out.vertices * k + 1);
  for (std::size_t x = 0; x < out.vertices; ++x)
    for (std::size_t r = 0; r <= k; ++r)
      out.offsets[x * k + r] = static_cast<std::uint32_t>(starts[x] + r * distinct[x]);
  const bool narrow = out.pixels <= 65536;
  if (narrow)
    out.columns16.resize(starts.back());
  else
    out.columns32.resize(starts.back());
  out.values.resize(starts.back());

  // Pass 2: row k of vertex x at pixel p is sum_j Psi[k, j] T_x[j, p], accumulated in double.
  std::vector<double> norms(out.vertices, 0.0);
  tbb::parallel_for(std::size_t{0}, out.vertices, [&](std::size_t x) {
    const std::vector<std::uint32_t>& c = columns[x];
    const std::size_t d = c.size();
    std::vector<double> acc(k * d, 0.0);
    const auto offsets = t.row_offsets();
    for (std::size_t j = 0; j < mm; ++j) {
      const std::size_t row = x * mm + j;
      for (std::uint32_t e = offsets[row]; e < offsets[row + 1]; ++e) {
        const auto at =
            static_cast<std::size_t>(std::lower_bound(c.begin(), c.end(), t.column(e)) - c.begin());
        const double v = t.value(e);
        for (std::size_t r = 0; r < k; ++r)
          acc[r * d + at] +=
              out.fold.light(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) * v;
      }
    }
    double norm = 0;
    for (std::size_t r = 0; r < k; ++r) {
      const std::size_t base = out.offsets[x * k + r];
      for (std::size_t i = 0; i < d; ++i) {
        const auto f = static_cast<float>(acc[r * d + i]);
        out.values[base + i] = f;
        norm += static_cast<double>(f) * f;
        if (narrow)
          out.columns16[base + i] = static_cast<std::uint16_t>(c[i]);
        else
          out.columns32[base + i] = c[i];
      }
    }
    norms[x] = norm;
    std::vector<std::uint32_t>().swap(columns[x]);
    progress.advance();
  });
  for (double n : norms) out.squared_norm += n;
  progress.finish();
  return out;
}

std::shared_ptr<const FoldedRows> BrdfSignalSource::rows(const TransferMatrix& t,
                                                         const HemisphereGrid& grid,
                                                         const BrdfSignalParams& params,
                                                         Progress& progress) {
  const std::string key = fmt::format("{} S={}", params.key(), grid.cell_count());
  const std::lock_guard lock(mutex_);
  if (rows_ && transfer_ == &t && key_ == key) return rows_;
  rows_.reset();  // the previous BRDF's rows go before the next are built
  rows_ = std::make_shared<const FoldedRows>(fold_transfer_rows(t, grid, params, progress));
  transfer_ = &t;
  key_ = key;
  return rows_;
}

std::shared_ptr<const FoldedRows> brdf_signal_rows(const TransferInput& input,
                                                   const BrdfSignalParams& params,
                                                   Progress& progress) {
  if (input.brdf_signal)
    return input.brdf_signal->rows(input.transfer, input.grid, params, progress);
  return std::make_shared<const FoldedRows>(
      fold_transfer_rows(input.transfer, input.grid, params, progress));
}

}  // namespace prt
