#include "bicluster/bicluster.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <span>

#include "bicluster/bicluster_budget.h"
#include "bicluster/bicluster_culling.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/sphere/lit_faces.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::bicluster {
namespace {

// Four floats in one 16-byte vector (GCC / Clang vector extension): RGB + pad.
typedef float F4 __attribute__((vector_size(16)));

class BiclusterCompressor final : public Compressor {
 public:
  BiclusterCompressor(std::uint64_t seed, int groups, double error)
      : seed_(seed), groups_(groups), error_(error) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    const TransferMatrix& t = input.transfer;
    Biclustering b;
    std::vector<std::int64_t> mass;
    {
      const SparseCounts counts = counts_of(t);
      SearchOptions options;
      options.seed = seed_;
      options.groups = groups_;
      options.rows_per_vertex = static_cast<std::size_t>(t.local_count());
      b = search(counts, options, progress);
      if (error_ > 0) mass = column_mass(counts);
    }
    BiclusterArrays a;
    if (error_ > 0) {
      const BudgetResult r = drop_within_budget(b, mass, error_);
      log_debug("{}: error {} dropped {} biclusters and {} residual terms ({} FLOPs), bound {}",
                kName, error_, r.dropped_biclusters, r.dropped_terms, r.flops_saved, r.bound);
      a = pack(b, t);
      a.error = error_;
      a.bound = r.bound;
    } else {
      a = pack(b, t);
    }
    return std::make_unique<BiclusterTransfer>(std::move(a));
  }

 private:
  std::uint64_t seed_;
  int groups_;
  double error_;
};

std::int16_t narrow_count(std::int64_t v) {
  PRT_CHECK(v != 0 && v >= std::numeric_limits<std::int16_t>::min() &&
                v <= std::numeric_limits<std::int16_t>::max(),
            "count {} does not fit the stored i16", v);
  return static_cast<std::int16_t>(v);
}

// Offsets of a CSR from per-row sizes.
std::vector<std::uint32_t> offsets_from(const std::vector<std::uint32_t>& sizes) {
  std::vector<std::uint32_t> off(sizes.size() + 1, 0);
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    PRT_CHECK(off[i] + std::uint64_t{sizes[i]} <= std::numeric_limits<std::uint32_t>::max(),
              "more than 2^32 - 1 entries");
    off[i + 1] = off[i] + sizes[i];
  }
  return off;
}

// Phase 2's row order. Consecutive rows should gather the same products, so that P (16 bytes per
// bicluster: 1.5 MB on the bunny, more than a core's L2 here) is read from L1/L2 rather than from
// L3 or memory. A bicluster's rows are one local direction of many vertices, so the rows of one
// vertex share almost nothing (1,075 distinct products in its 1,079 gathers on the bunny): vertex
// by vertex, half of the gathers reused a line last read more than 128 KiB earlier, and a process
// streaming memory on the other core made the relight 2x slower. Here biclusters take, largest
// first (ties: search order), their rows not yet placed; rows without a bicluster come last. Then,
// within windows of kRowWindow rows, longer rows first, so that the four lanes of a slice have
// similar lengths (less padding). compressors/bicluster/README.md, "Row order", has the
// measurements.
std::vector<std::uint32_t> phase2_row_order(std::size_t rows,
                                            const std::vector<std::uint32_t>& sizes,
                                            const std::vector<std::uint32_t>& row_off,
                                            const auto& rows_of) {
  std::vector<std::uint32_t> by_size(sizes.size());
  std::iota(by_size.begin(), by_size.end(), std::uint32_t{0});
  std::stable_sort(by_size.begin(), by_size.end(),
                   [&](std::uint32_t x, std::uint32_t y) { return sizes[x] > sizes[y]; });
  std::vector<std::uint8_t> placed(rows, 0);
  std::vector<std::uint32_t> order;
  order.reserve(rows);
  for (std::uint32_t i : by_size) {
    rows_of(i, [&](std::uint32_t j) {
      if (!placed[j]) {
        placed[j] = 1;
        order.push_back(j);
      }
    });
  }
  for (std::size_t j = 0; j < rows; ++j)
    if (!placed[j]) order.push_back(static_cast<std::uint32_t>(j));
  auto length = [&](std::uint32_t j) { return row_off[j + 1] - row_off[j]; };
  for (std::size_t w = 0; w < order.size(); w += kRowWindow) {
    std::stable_sort(
        order.begin() + static_cast<std::ptrdiff_t>(w),
        order.begin() + static_cast<std::ptrdiff_t>(std::min(w + kRowWindow, order.size())),
        [&](std::uint32_t x, std::uint32_t y) { return length(x) > length(y); });
  }
  return order;
}

}  // namespace

std::string_view to_string(DeviceIds ids) {
  switch (ids) {
    case DeviceIds::kAuto:
      return "auto";
    case DeviceIds::kU16:
      return "u16";
    case DeviceIds::kU32:
      return "u32";
  }
  return "?";
}

SparseCounts counts_of(const TransferMatrix& t) {
  SparseCounts s;
  s.rows = t.rows();
  s.cols = t.cols();
  s.offsets.assign(t.row_offsets().begin(), t.row_offsets().end());
  s.columns.resize(t.nnz());
  for (std::size_t i = 0; i < t.nnz(); ++i) s.columns[i] = t.column(i);
  s.values.assign(t.counts().begin(), t.counts().end());
  return s;
}

std::size_t BiclusterArrays::incidences() const {
  std::size_t n = 0;
  for (std::size_t s = 0; s < slice_count(); ++s)
    for (int lane = 0; lane < kSliceRows; ++lane)
      for_each_id(s, lane, [&n](std::uint32_t) { ++n; });
  return n;
}

namespace {

// The items of a result: its biclusters, then its residual terms (consolidated) as 1x1
// biclusters. A position can be seeded as a residual term more than once (a later bicluster may
// leave a residual where an earlier seed was removed): consolidation sums them.
struct PackItems {
  const Biclustering& b;
  Biclustering residual;

  explicit PackItems(const Biclustering& result) : b(result) {
    residual.rows = b.rows;
    residual.cols = b.cols;
    residual.residual = b.residual;
    consolidate_residual(residual);
  }
  std::size_t count() const { return b.biclusters.size() + residual.residual.size(); }
  const Term& term(std::size_t i) const { return residual.residual[i - b.biclusters.size()]; }
  template <typename Visit>
  void rows_of(std::size_t i, Visit&& visit) const {
    if (i < b.biclusters.size()) {
      for (std::uint32_t j : b.biclusters[i].rows) visit(j);
    } else {
      visit(term(i).row);
    }
  }
  std::uint32_t size(std::size_t i) const {
    return i < b.biclusters.size() ? static_cast<std::uint32_t>(b.biclusters[i].rows.size()) : 1;
  }
};

// Per row, the ids of the items touching it (CSR: offsets per row + 1, ids).
struct RowIncidence {
  std::vector<std::uint32_t> offsets, ids;
};

RowIncidence row_incidence(const PackItems& items, std::size_t rows) {
  std::vector<std::uint32_t> per_row(rows, 0);
  for (std::size_t i = 0; i < items.count(); ++i)
    items.rows_of(i, [&](std::uint32_t j) { ++per_row[j]; });
  RowIncidence inc;
  inc.offsets = offsets_from(per_row);
  inc.ids.resize(inc.offsets.back());
  std::vector<std::uint32_t> fill(inc.offsets.begin(), inc.offsets.end() - 1);
  for (std::size_t i = 0; i < items.count(); ++i)
    items.rows_of(i, [&](std::uint32_t j) { inc.ids[fill[j]++] = static_cast<std::uint32_t>(i); });
  return inc;
}

// Item ids by first use in phase 2's row order, skipping the zero slots (multiples of
// kZeroStride). Rewrites `inc.ids` to the new ids, sorted within each row, and returns, per new
// id, the item it stands for (kNoItem for a zero slot).
constexpr auto kNoItem = std::numeric_limits<std::uint32_t>::max();

std::vector<std::uint32_t> number_by_first_use(RowIncidence& inc, std::size_t items,
                                               std::span<const std::uint32_t> order) {
  std::vector<std::uint32_t> renumber(items, kNoItem);
  std::uint64_t next = 1;  // id 0 is the first zero slot
  std::size_t numbered = 0;
  for (std::uint32_t row : order) {
    for (std::uint32_t q = inc.offsets[row]; q < inc.offsets[row + 1]; ++q) {
      if (renumber[inc.ids[q]] != kNoItem) continue;
      if (next % kZeroStride == 0) ++next;
      PRT_CHECK(next < std::numeric_limits<std::uint32_t>::max(), "bicluster ids exceed u32");
      renumber[inc.ids[q]] = static_cast<std::uint32_t>(next++);
      ++numbered;
    }
  }
  PRT_CHECK(numbered == items, "{} of {} biclusters have no row", items - numbered, items);
  for (std::uint32_t& id : inc.ids) id = renumber[id];
  for (std::size_t j = 0; j + 1 < inc.offsets.size(); ++j)
    std::sort(inc.ids.begin() + inc.offsets[j], inc.ids.begin() + inc.offsets[j + 1]);
  std::vector<std::uint32_t> item_of(static_cast<std::size_t>(next), kNoItem);
  for (std::size_t i = 0; i < items; ++i) item_of[renumber[i]] = static_cast<std::uint32_t>(i);
  return item_of;
}

// Phase 1 arrays in the new id order; zero slots have no columns.
void pack_phase1(const PackItems& items, std::span<const std::uint32_t> item_of,
                 BiclusterArrays& a) {
  for (std::uint32_t i : item_of) {
    if (i == kNoItem) {
      // a zero slot
    } else if (i < items.b.biclusters.size()) {
      const Bicluster& bc = items.b.biclusters[i];
      for (std::size_t q = 0; q < bc.cols.size(); ++q) {
        a.bic_columns.push_back(bc.cols[q]);
        a.bic_constants.push_back(narrow_count(bc.constants[q]));
      }
    } else {
      a.bic_columns.push_back(items.term(i).col);
      a.bic_constants.push_back(narrow_count(items.term(i).value));
    }
    PRT_CHECK(a.bic_columns.size() <= std::numeric_limits<std::uint32_t>::max(),
              "more than 2^32 - 1 bicluster columns");
    a.bic_col_offsets.push_back(static_cast<std::uint32_t>(a.bic_columns.size()));
  }
}

std::uint32_t next_zero_slot(std::uint32_t id) {
  return (id / kZeroStride + 1) * kZeroStride;
}

// One lane's codes: deltas from `base` to each of `ids`, crossing gaps of 2^16 or more through
// zero slots. Returns the id the lane ends on.
std::uint32_t encode_lane(std::span<const std::uint32_t> ids, std::uint32_t base,
                          std::vector<std::uint16_t>& codes) {
  codes.clear();
  std::uint32_t id = base;
  for (const std::uint32_t target : ids) {
    if (target - id > 0xffff) {
      const std::uint32_t z = next_zero_slot(id);
      codes.push_back(static_cast<std::uint16_t>(z - id));
      id = z;
      while (target - id > 0xffff) {
        codes.push_back(static_cast<std::uint16_t>(kZeroStride));
        id += kZeroStride;
      }
    }
    codes.push_back(static_cast<std::uint16_t>(target - id));
    id = target;
  }
  return id;
}

// Phase 2: SELL-4 over the rows in phase 2's order, lanes delta-coded from the smallest id of
// the slice, shorter lanes padded onto a zero slot and zero deltas.
void pack_phase2(const RowIncidence& inc, std::span<const std::uint32_t> order,
                 BiclusterArrays& a) {
  const std::size_t rows = a.rows();
  const std::size_t slices = a.slice_count_for_rows();
  a.slice_rows.reserve(slices * kSliceRows);
  a.slice_offsets.reserve(slices + 1);
  a.slice_base.reserve(slices);
  a.slice_codes.reserve(inc.ids.size() + inc.ids.size() / 8);
  std::vector<std::uint16_t> lane_codes[kSliceRows];
  for (std::size_t s = 0; s < slices; ++s) {
    std::span<const std::uint32_t> lane_ids[kSliceRows];
    std::uint32_t base = std::numeric_limits<std::uint32_t>::max();
    for (int lane = 0; lane < kSliceRows; ++lane) {
      const std::size_t slot = s * kSliceRows + static_cast<std::size_t>(lane);
      if (slot >= rows) {
        a.slice_rows.push_back(static_cast<std::uint32_t>(rows));
        continue;
      }
      const std::uint32_t row = order[slot];
      a.slice_rows.push_back(row);
      lane_ids[lane] = std::span<const std::uint32_t>(inc.ids).subspan(
          inc.offsets[row], inc.offsets[row + 1] - inc.offsets[row]);
      if (!lane_ids[lane].empty()) base = std::min(base, lane_ids[lane].front());
    }
    if (base == std::numeric_limits<std::uint32_t>::max()) base = 0;  // empty: a zero slot
    std::size_t longest = 0;
    std::uint32_t lane_end[kSliceRows];
    for (int lane = 0; lane < kSliceRows; ++lane) {
      lane_end[lane] = encode_lane(lane_ids[lane], base, lane_codes[lane]);
      longest = std::max(longest, lane_codes[lane].size());
    }
    for (int lane = 0; lane < kSliceRows; ++lane) {
      auto& codes = lane_codes[lane];
      if (codes.size() == longest) continue;
      // An empty lane sits at the slice's base, a real bicluster (or zero when the slice is
      // empty, then longest = 0): step to the next zero slot first.
      const std::uint32_t id = lane_end[lane];
      codes.push_back(
          static_cast<std::uint16_t>(id % kZeroStride == 0 ? 0 : next_zero_slot(id) - id));
      codes.resize(longest, 0);
    }
    for (std::size_t q = 0; q < longest; ++q)
      for (const auto& codes : lane_codes) a.slice_codes.push_back(codes[q]);
    PRT_CHECK(a.slice_codes.size() <= std::numeric_limits<std::uint32_t>::max(),
              "more than 2^32 - 1 slice codes");
    a.slice_base.push_back(base);
    a.slice_offsets.push_back(static_cast<std::uint32_t>(a.slice_codes.size()));
  }
}

}  // namespace

BiclusterArrays pack(const Biclustering& b, const TransferMatrix& t) {
  BiclusterArrays a;
  a.vertices = t.vertex_count();
  a.local_count = t.local_count();
  a.pixel_count = static_cast<int>(t.cols());
  a.supersampling = t.supersampling();
  const std::size_t rows = a.rows();
  PRT_CHECK(rows < std::numeric_limits<std::uint32_t>::max(), "{} rows exceed u32 ids", rows);

  const PackItems items(b);
  const std::size_t nb = items.count();
  PRT_CHECK(nb < std::numeric_limits<std::uint32_t>::max(), "{} biclusters exceed u32 ids", nb);
  RowIncidence inc = row_incidence(items, rows);
  std::vector<std::uint32_t> sizes(nb);
  for (std::size_t i = 0; i < nb; ++i) sizes[i] = items.size(i);
  const std::vector<std::uint32_t> order = phase2_row_order(
      rows, sizes, inc.offsets, [&](std::size_t i, auto&& visit) { items.rows_of(i, visit); });
  const std::vector<std::uint32_t> item_of = number_by_first_use(inc, nb, order);
  pack_phase1(items, item_of, a);
  pack_phase2(inc, order, a);
  return a;
}

SparseCounts reconstruct(const BiclusterArrays& a) {
  Biclustering b;
  b.rows = a.rows();
  b.cols = static_cast<std::size_t>(a.pixel_count);
  const std::size_t nb = a.bicluster_count();
  b.biclusters.resize(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    for (std::uint32_t p = a.bic_col_offsets[i]; p < a.bic_col_offsets[i + 1]; ++p) {
      b.biclusters[i].cols.push_back(a.bic_columns[p]);
      b.biclusters[i].constants.push_back(a.bic_constants[p]);
    }
  }
  for (std::size_t s = 0; s < a.slice_count(); ++s) {
    for (int lane = 0; lane < kSliceRows; ++lane) {
      const std::uint32_t row = a.slice_rows[s * kSliceRows + static_cast<std::size_t>(lane)];
      a.for_each_id(s, lane, [&](std::uint32_t id) { b.biclusters.at(id).rows.push_back(row); });
    }
  }
  // Biclustering::reconstruct sums per position (zero slots add nothing); the row order within
  // a bicluster is irrelevant.
  return b.reconstruct();
}

BiclusterTransfer::BiclusterTransfer(BiclusterArrays arrays)
    : a_(std::move(arrays)),
      incidences_(a_.incidences()),
      faces_(bicluster_faces(a_)),
      row_lanes_(row_lanes(a_)) {}

StorageReport BiclusterTransfer::storage() const {
  const std::uint64_t col_bytes = narrow() ? 2 : 4;
  const std::string col_type = narrow() ? "u16" : "u32";
  const std::uint64_t lane_bytes = narrow_rows() ? 2 : 4;
  const std::string lane_type = narrow_rows() ? "u16" : "u32";
  StorageReport r;
  r.components.push_back({"bic_col_offsets", a_.bic_col_offsets.size() * std::uint64_t{4},
                          "u32 per bicluster + 1: first entry of its columns/constants"});
  r.components.push_back({"bic_columns", a_.bic_columns.size() * col_bytes,
                          col_type + " per bicluster column: global pixel k, increasing"});
  r.components.push_back({"bic_constants", a_.bic_constants.size() * std::uint64_t{2},
                          "i16 per bicluster column: constant t_m as a signed count (x 1/s^2)"});
  r.components.push_back({"slice_offsets", a_.slice_offsets.size() * std::uint64_t{4},
                          "u32 per slice of 4 rows + 1: first entry of the slice's codes"});
  r.components.push_back(
      {"slice_rows", a_.slice_rows.size() * lane_bytes,
       lane_type + " per slice lane: the lane's row (rows: none), phase 2's row order"});
  r.components.push_back({"slice_base", a_.slice_base.size() * std::uint64_t{4},
                          "u32 per slice: the smallest bicluster id of its lanes"});
  r.components.push_back(
      {"slice_codes", a_.slice_codes.size() * std::uint64_t{2},
       "u16 per slice step and lane (SELL-4): bicluster id delta; zero slots pad"});
  r.components.push_back({"scale", 4, "f32 once: 1/s^2 (stored as s in the metadata)"});
  return r;
}

double BiclusterTransfer::flops_per_relight() const {
  // sum (r_i + 2 l_i - 1) = incidences + 2 columns - biclusters.
  return static_cast<double>(incidences_) + 2.0 * static_cast<double>(a_.bic_columns.size()) -
         static_cast<double>(a_.real_bicluster_count());
}

LightCoeffs BiclusterTransfer::project_light(const Cubemap& radiance) const {
  return pixel_light(radiance, static_cast<std::size_t>(a_.pixel_count), kName);
}

void BiclusterTransfer::prepare_output(LocalRadiance& out) const {
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
}

// RGB + pad as one SSE register: float4 loads and adds, as the OpenCL kernels do. Float
// accumulation: a row's rounding error is at most about (its terms) x 2^-24 x (the sum of
// their magnitudes); with ~20 terms per row that is ~1e-7 of the largest value (measured:
// ~1e-7 relative L2 against the double product; the conformance suite allows 1e-6).
void BiclusterTransfer::phase1(const LightCoeffs& light, std::uint32_t lit, float* products) const {
  F4* p = reinterpret_cast<F4*>(products);
  const std::size_t nb = a_.bicluster_count();
  // Not value-initialised: every element is written below.
  const auto light4 = std::make_unique_for_overwrite<F4[]>(light.values.size());
  for (std::size_t k = 0; k < light.values.size(); ++k)
    light4[k] = F4{light.values[k].x, light.values[k].y, light.values[k].z, 0.f};
  // Phase 1 (Algorithm 2, lines 1-3): one RGB scalar per bicluster (0 for the zero slots).
  p[a_.product_count() - 1] = F4{0.f, 0.f, 0.f, 0.f};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 8192), [&](const auto& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      F4 acc{0.f, 0.f, 0.f, 0.f};
      if ((faces_[i] & lit) != 0) {
        for (std::uint32_t q = a_.bic_col_offsets[i]; q < a_.bic_col_offsets[i + 1]; ++q)
          acc += static_cast<float>(a_.bic_constants[q]) * light4[a_.bic_columns[q]];
      }
      p[i] = acc;
    }
  });
}

void BiclusterTransfer::phase2(const float* products, const std::uint32_t* slices,
                               const std::uint8_t* lanes, std::size_t count,
                               LocalRadiance& out) const {
  // Phase 2 (lines 4-11): per slice, four rows gathered in lockstep. Each row is summed by one
  // task in a fixed order, so the result does not depend on the thread count.
  const std::size_t rows = a_.rows();
  const float scale = static_cast<float>(a_.scale());
  const F4* pp = reinterpret_cast<const F4*>(products);
  const std::uint16_t* codes = a_.slice_codes.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 512), [&](const auto& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      const std::size_t s = slices ? slices[i] : i;
      const unsigned store = lanes ? lanes[i] : 0xfu;
      F4 a0{0.f, 0.f, 0.f, 0.f}, a1 = a0, a2 = a0, a3 = a0;
      std::uint32_t i0 = a_.slice_base[s], i1 = i0, i2 = i0, i3 = i0;
      const std::uint16_t* c = codes + a_.slice_offsets[s];
      const std::uint16_t* end = codes + a_.slice_offsets[s + 1];
      for (; c < end; c += kSliceRows) {
        i0 += c[0];
        i1 += c[1];
        i2 += c[2];
        i3 += c[3];
        a0 += pp[i0];
        a1 += pp[i1];
        a2 += pp[i2];
        a3 += pp[i3];
      }
      const F4 acc[kSliceRows] = {a0, a1, a2, a3};
      for (int lane = 0; lane < kSliceRows; ++lane) {
        const std::uint32_t row = a_.slice_rows[s * kSliceRows + lane];
        if (row >= rows || (store >> lane & 1u) == 0) continue;
        const F4 v = acc[lane] * scale;
        out.values[row] = Rgb(v[0], v[1], v[2]);
      }
    }
  });
}

void BiclusterTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(a_.pixel_count), kName);
  relight_faces(light, lit_faces(light.values), out);
}

void BiclusterTransfer::relight_faces(const LightCoeffs& light, std::uint32_t lit,
                                      LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(a_.pixel_count), kName);
  prepare_output(out);
  // P is ~1.5 MB on the bunny: not value-initialised, phase 1 writes every product read.
  const auto p = std::make_unique_for_overwrite<F4[]>(a_.product_count());
  phase1(light, lit, reinterpret_cast<float*>(p.get()));
  phase2(reinterpret_cast<const float*>(p.get()), nullptr, nullptr, a_.slice_count(), out);
}

void BiclusterTransfer::relight_vertices(const LightCoeffs& light,
                                         std::span<const std::uint32_t> vertices,
                                         LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(a_.pixel_count), kName);
  check_vertex_subset(vertices, a_.vertices, kName);
  prepare_output(out);
  const SliceSubset subset = slices_of(a_.slice_count(), a_.local_count, row_lanes_, vertices);
  const auto p = std::make_unique_for_overwrite<F4[]>(a_.product_count());
  phase1(light, lit_faces(light.values), reinterpret_cast<float*>(p.get()));
  phase2(reinterpret_cast<const float*>(p.get()), subset.slices.data(), subset.lanes.data(),
         subset.slices.size(), out);
}

std::unique_ptr<DeviceRelighter> BiclusterTransfer::upload(ClContext& context,
                                                           const ParamSet& device_options) const {
  return upload_arrays(context, a_,
                       device_options.get_enum<DeviceIds>("opencl_ids", {{"auto", DeviceIds::kAuto},
                                                                         {"u16", DeviceIds::kU16},
                                                                         {"u32", DeviceIds::kU32}}),
                       device_options.get_bool("opencl_skip_faces"));
}

void BiclusterTransfer::save(ArchiveWriter& w) const {
  w.add_meta("bicluster_version", kStateVersion);
  w.add_meta("vertices", a_.vertices);
  w.add_meta("local_count", a_.local_count);
  w.add_meta("pixel_count", a_.pixel_count);
  w.add_meta("supersampling", a_.supersampling);
  w.add_meta("error", a_.error);
  w.add_meta("error_bound", a_.bound);
  w.add_section("bic_col_offsets", a_.bic_col_offsets);
  w.add_indices("bic_columns", a_.bic_columns, narrow());
  w.add_section("bic_constants", a_.bic_constants);
  w.add_section("slice_offsets", a_.slice_offsets);
  w.add_indices("slice_rows", a_.slice_rows, narrow_rows());
  w.add_section("slice_base", a_.slice_base);
  w.add_section("slice_codes", a_.slice_codes);
}

namespace {

// What a lossless archive stands for can be checked without T: its sum of biclusters must be a
// matrix of sample counts. Pixel k's s^2 samples land, at vertex v, in at most one local bin
// each, so every entry is in [0, s^2] and so is the sum over v's M rows of column k. A column
// out of order, an id pointing at the wrong bicluster or a damaged constant breaks one of
// them, however consistent the checksums are. Parallel over vertices, O(stored incidences).
void verify_counts(const BiclusterArrays& a, const std::vector<std::uint32_t>& lane_of_row,
                   const std::filesystem::path& file) {
  const std::int64_t max_count = static_cast<std::int64_t>(a.supersampling) * a.supersampling;
  const std::size_t m = static_cast<std::size_t>(a.local_count);
  const std::size_t n = static_cast<std::size_t>(a.pixel_count);
  std::atomic<bool> failed{false};
  std::mutex mutex;
  std::string problem;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.vertices, 64), [&](const auto& range) {
    std::vector<std::int64_t> row_sum(n, 0), vertex_sum(n, 0);
    std::vector<std::uint32_t> row_touched, vertex_touched;
    auto fail = [&](std::string what) {
      const std::lock_guard lock(mutex);
      if (!failed.exchange(true)) problem = std::move(what);
    };
    for (std::size_t v = range.begin(); v != range.end() && !failed.load(); ++v) {
      for (std::size_t j = 0; j < m; ++j) {
        const std::size_t row = v * m + j;
        const std::uint32_t p = lane_of_row[row];
        a.for_each_id(p / kSliceRows, static_cast<int>(p % kSliceRows), [&](std::uint32_t id) {
          for (std::uint32_t q = a.bic_col_offsets[id]; q < a.bic_col_offsets[id + 1]; ++q) {
            const std::uint32_t k = a.bic_columns[q];
            if (row_sum[k] == 0) row_touched.push_back(k);
            row_sum[k] += a.bic_constants[q];
          }
        });
        for (const std::uint32_t k : row_touched) {
          const std::int64_t c = row_sum[k];
          if (c < 0 || c > max_count)
            fail(fmt::format("row {} column {} sums to {} samples, outside [0, {}]", row, k, c,
                             max_count));
          if (vertex_sum[k] == 0 && c != 0) vertex_touched.push_back(k);
          vertex_sum[k] += c;
          row_sum[k] = 0;
        }
        row_touched.clear();
      }
      for (const std::uint32_t k : vertex_touched) {
        if (vertex_sum[k] > max_count)
          fail(
              fmt::format("vertex {} receives {} samples of pixel {} over its {} bins, more than "
                          "the pixel's {}",
                          v, vertex_sum[k], k, m, max_count));
        vertex_sum[k] = 0;
      }
      vertex_touched.clear();
    }
  });
  if (failed)
    throw InputError(file,
                     fmt::format("{}: the archive is not a lossless transfer: {}", kName, problem));
}

}  // namespace

std::unique_ptr<CompressedTransfer> BiclusterTransfer::load(const ArchiveReader& r) {
  const int version = r.meta_value<int>("bicluster_version");
  if (version != kStateVersion)
    throw InputError(
        r.path(), fmt::format("{} state version {} is not the version {} this build reads", kName,
                              version, kStateVersion));
  BiclusterArrays a;
  a.vertices = r.meta_value<std::size_t>("vertices");
  a.local_count = r.meta_value<int>("local_count");
  a.pixel_count = r.meta_value<int>("pixel_count");
  a.supersampling = r.meta_value<int>("supersampling");
  a.error = r.meta_value<double>("error");
  a.bound = r.meta_value<double>("error_bound");
  // Rows index the u32 lanes (and rows() is the empty lane's sentinel): checked without
  // overflowing the product.
  if (a.local_count <= 0 || a.pixel_count <= 0 || a.supersampling <= 0 ||
      a.vertices >= std::numeric_limits<std::uint32_t>::max() / std::size_t(a.local_count))
    throw InputError(r.path(), fmt::format("{}: invalid shape in the metadata", kName));
  if (!(a.error >= 0 && a.error <= 1 && a.bound >= 0 && a.bound <= a.error))
    throw InputError(r.path(),
                     fmt::format("{}: error {} / bound {} out of range", kName, a.error, a.bound));
  const std::size_t slices = a.slice_count_for_rows();
  a.bic_col_offsets = r.section<std::uint32_t>("bic_col_offsets");
  a.bic_columns = r.indices("bic_columns");
  a.bic_constants = r.section<std::int16_t>("bic_constants", a.bic_columns.size());
  a.slice_offsets = r.section<std::uint32_t>("slice_offsets", slices + 1);
  a.slice_rows = r.indices("slice_rows", slices * kSliceRows);
  a.slice_base = r.section<std::uint32_t>("slice_base", slices);
  a.slice_codes = r.section<std::uint16_t>("slice_codes");
  auto invalid = [&](const std::string& what) {
    return InputError(r.path(), fmt::format("{}: {}", kName, what));
  };
  auto check_offsets = [&](const std::vector<std::uint32_t>& off, std::size_t total,
                           const char* name, std::uint32_t multiple) {
    if (off.empty() || off.front() != 0 || off.back() != total ||
        !std::is_sorted(off.begin(), off.end()) ||
        std::any_of(off.begin(), off.end(), [&](std::uint32_t o) { return o % multiple != 0; }))
      throw invalid(fmt::format("section {} is not a valid offset array", name));
  };
  check_offsets(a.bic_col_offsets, a.bic_columns.size(), "bic_col_offsets", 1);
  check_offsets(a.slice_offsets, a.slice_codes.size(), "slice_offsets", kSliceRows);
  for (std::size_t i = 0; i < a.bicluster_count(); i += kZeroStride)
    if (a.bic_col_offsets[i + 1] != a.bic_col_offsets[i])
      throw invalid(fmt::format("zero slot {} has columns", i));
  const auto n = static_cast<std::uint32_t>(a.pixel_count);
  if (std::any_of(a.bic_columns.begin(), a.bic_columns.end(), [&](auto k) { return k >= n; }))
    throw invalid(fmt::format("a column id is >= N = {}", n));
  for (std::size_t i = 0; i < a.bicluster_count(); ++i)
    for (std::uint32_t q = a.bic_col_offsets[i] + 1; q < a.bic_col_offsets[i + 1]; ++q)
      if (a.bic_columns[q] <= a.bic_columns[q - 1])
        throw invalid(fmt::format("bicluster {}'s columns are not increasing ({} after {})", i,
                                  a.bic_columns[q], a.bic_columns[q - 1]));
  if (std::any_of(a.bic_constants.begin(), a.bic_constants.end(),
                  [](std::int16_t c) { return c == 0; }))
    throw invalid("a bicluster column has the constant 0 (the search never stores one)");
  // Every row in exactly one lane; a lane's ids below B (no id in an empty lane).
  const std::size_t nb = a.bicluster_count(), rows = a.rows();
  std::vector<std::uint8_t> seen(rows, 0);
  for (std::size_t s = 0; s < slices; ++s) {
    for (int lane = 0; lane < kSliceRows; ++lane) {
      const std::uint32_t row = a.slice_rows[s * kSliceRows + static_cast<std::size_t>(lane)];
      if (row > rows) throw invalid(fmt::format("lane row {} > rows = {}", row, rows));
      if (row < rows && seen[row]++) throw invalid(fmt::format("row {} is listed twice", row));
      std::uint64_t id = a.slice_base[s];
      for (std::uint32_t q = a.slice_offsets[s] + static_cast<std::uint32_t>(lane);
           q < a.slice_offsets[s + 1]; q += kSliceRows) {
        id += a.slice_codes[q];
        const bool zero = id % kZeroStride == 0;
        if ((zero && id >= a.product_count()) || (!zero && (id >= nb || row == rows)))
          throw invalid(fmt::format("slice {} lane {} reads product {} of {}", s, lane, id, nb));
      }
    }
  }
  if (std::count(seen.begin(), seen.end(), 1) != static_cast<std::ptrdiff_t>(rows))
    throw invalid(fmt::format("the slices do not list all {} rows", rows));
  if (a.bound == 0) verify_counts(a, row_lanes(a), r.path());
  return std::make_unique<BiclusterTransfer>(std::move(a));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "constant-column biclustering of T, two-phase relight (Sun et al., biclustering for "
      "all-frequency bi-scale PRT); lossless at the default error=0";
  // At the default parameters (error = 0): the conformance suite checks the default result.
  e.lossless = true;
  e.collective = true;       // its row groups go through a work queue over the ranks
  e.cost_hint_seconds = 20;  // where it was measured: docs/cli.md, "Cost hints"
  e.params = {
      {"groups",
       ParamType::kInt,
       std::to_string(kDefaultGroups),
       1.0,
       4096.0,
       {},
       "row groups (contiguous whole vertices) searched in parallel; the result depends on the "
       "parameters only, not on the thread count"},
      {"error",
       ParamType::kReal,
       "0",
       0.0,
       1.0,
       {},
       "lossy mode: relative L1 error budget E per light (0 = lossless); drops biclusters and "
       "residual terms while every column loses at most E of its L1 mass"},
  };
  // Narrowed to the lossy budgets: E = 0 is the lossless point, and a log sweep needs E > 0.
  e.size_knob = SizeKnob{.key = "error",
                         .direction = SizeKnob::Direction::kLargerIsLessStorage,
                         .min = 1e-3,
                         .max = 1.0,
                         .scale = SizeKnob::Scale::kLog};
  e.device_params = {
      {"opencl_ids",
       ParamType::kEnum,
       "auto",
       std::nullopt,
       std::nullopt,
       {"auto", "u16", "u32"},
       "OpenCL phase 2 ids: u16 = the stored deltas decoded in the kernel, u32 = expanded at "
       "upload (twice the bytes, no decoding), auto = u32 on CPUs, u16 on GPUs"},
      {"opencl_skip_faces",
       ParamType::kBool,
       "true",
       std::nullopt,
       std::nullopt,
       {},
       "phase 1 skips biclusters whose columns all lie on cube faces the light leaves black "
       "(bit-identical; false computes them, for comparisons)"},
  };
  e.create = [](const ParamSet& params) -> std::unique_ptr<Compressor> {
    return std::make_unique<BiclusterCompressor>(static_cast<std::uint64_t>(params.get_int("seed")),
                                                 static_cast<int>(params.get_int("groups")),
                                                 params.get_real("error"));
  };
  e.load = &BiclusterTransfer::load;
  // 2: grouped parallel search, merge of identical biclusters, lossy mode, state version 2.
  // 3: phase 2's row order (rows sharing biclusters adjacent), state version 3.
  // 4: the device option opencl_ids left the saved state, state version 4.
  e.version = 4;
  e.published = {
      {"chair",
       {{"error", "0"}},
       "lossless: 36.4 MB",
       "Sun et al. 2008, Fig. 6; their chair has 16K vertices x 64 local directions"},
  };
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::bicluster
