#include "bicluster/bicluster.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "prtlab/archive.h"
#include "prtlab/error.h"
#include "prtlab/log.h"
#include "prtlab/transfer_matrix.h"

namespace prt::bicluster {
namespace {

class BiclusterCompressor final : public Compressor {
 public:
  explicit BiclusterCompressor(std::uint64_t seed) : seed_(seed) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    const TransferMatrix& t = input.transfer;
    if (t.cols() != static_cast<std::size_t>(input.cubemap.pixel_count()) ||
        t.local_count() != input.grid.cell_count()) {
      throw ParameterError(fmt::format(
          "{}: the transfer is {} x {} per vertex but the bases give M = {}, N = {}", kName,
          t.local_count(), t.cols(), input.grid.cell_count(), input.cubemap.pixel_count()));
    }
    const Biclustering b = search(counts_of(t), seed_, progress);
    return std::make_unique<BiclusterTransfer>(pack(b, t));
  }

 private:
  std::uint64_t seed_;
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
  for (std::size_t i = 0; i < sizes.size(); ++i) off[i + 1] = off[i] + sizes[i];
  return off;
}

}  // namespace

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

BiclusterArrays pack(const Biclustering& b, const TransferMatrix& t) {
  BiclusterArrays a;
  a.vertices = t.vertex_count();
  a.local_count = t.local_count();
  a.pixel_count = static_cast<int>(t.cols());
  a.supersampling = t.supersampling();
  const std::size_t rows = a.rows();
  std::vector<std::uint32_t> per_row(rows, 0);
  for (const Bicluster& bc : b.biclusters) {
    for (std::size_t m = 0; m < bc.cols.size(); ++m) {
      a.bic_columns.push_back(bc.cols[m]);
      a.bic_constants.push_back(narrow_count(bc.constants[m]));
    }
    a.bic_col_offsets.push_back(static_cast<std::uint32_t>(a.bic_columns.size()));
    for (std::uint32_t j : bc.rows) ++per_row[j];
  }
  a.row_bic_offsets = offsets_from(per_row);
  a.row_bics.resize(a.row_bic_offsets.back());
  std::vector<std::uint32_t> fill(a.row_bic_offsets.begin(), a.row_bic_offsets.end() - 1);
  for (std::size_t i = 0; i < b.biclusters.size(); ++i)
    for (std::uint32_t j : b.biclusters[i].rows)
      a.row_bics[fill[j]++] = static_cast<std::uint32_t>(i);

  // A position can be seeded as a residual term more than once (a later bicluster may leave a
  // residual where an earlier seed was removed): sum them.
  std::vector<Term> terms = b.residual;
  std::sort(terms.begin(), terms.end(), [](const Term& x, const Term& y) {
    return x.row != y.row ? x.row < y.row : x.col < y.col;
  });
  std::fill(per_row.begin(), per_row.end(), 0);
  for (std::size_t i = 0; i < terms.size();) {
    std::int64_t sum = 0;
    std::size_t e = i;
    for (; e < terms.size() && terms[e].row == terms[i].row && terms[e].col == terms[i].col; ++e)
      sum += terms[e].value;
    if (sum != 0) {
      a.res_columns.push_back(terms[i].col);
      a.res_counts.push_back(narrow_count(sum));
      ++per_row[terms[i].row];
    }
    i = e;
  }
  a.res_offsets = offsets_from(per_row);
  return a;
}

SparseCounts reconstruct(const BiclusterArrays& a) {
  Biclustering b;
  b.rows = a.rows();
  b.cols = static_cast<std::size_t>(a.pixel_count);
  b.biclusters.resize(a.bicluster_count());
  for (std::size_t i = 0; i < a.bicluster_count(); ++i) {
    for (std::uint32_t p = a.bic_col_offsets[i]; p < a.bic_col_offsets[i + 1]; ++p) {
      b.biclusters[i].cols.push_back(a.bic_columns[p]);
      b.biclusters[i].constants.push_back(a.bic_constants[p]);
    }
  }
  for (std::size_t j = 0; j < b.rows; ++j) {
    for (std::uint32_t p = a.row_bic_offsets[j]; p < a.row_bic_offsets[j + 1]; ++p)
      b.biclusters[a.row_bics[p]].rows.push_back(static_cast<std::uint32_t>(j));
    for (std::uint32_t p = a.res_offsets[j]; p < a.res_offsets[j + 1]; ++p)
      b.residual.push_back({static_cast<std::uint32_t>(j), a.res_columns[p], a.res_counts[p]});
  }
  return b.reconstruct();
}

BiclusterTransfer::BiclusterTransfer(BiclusterArrays arrays) : a_(std::move(arrays)) {}

StorageReport BiclusterTransfer::storage() const {
  const std::uint64_t col_bytes = narrow() ? 2 : 4;
  const std::string col_type = narrow() ? "u16" : "u32";
  StorageReport r;
  r.components.push_back({"bic_col_offsets", a_.bic_col_offsets.size() * std::uint64_t{4},
                          "u32 per bicluster + 1: first entry of its columns/constants"});
  r.components.push_back({"bic_columns", a_.bic_columns.size() * col_bytes,
                          col_type + " per bicluster column: global pixel k, increasing"});
  r.components.push_back({"bic_constants", a_.bic_constants.size() * std::uint64_t{2},
                          "i16 per bicluster column: constant t_m as a signed count (x 1/s^2)"});
  r.components.push_back({"row_bic_offsets", a_.row_bic_offsets.size() * std::uint64_t{4},
                          "u32 per row + 1: first entry of the row's bicluster ids"});
  r.components.push_back({"row_bics", a_.row_bics.size() * std::uint64_t{4},
                          "u32 per (row, bicluster) incidence: bicluster id, increasing (I_j)"});
  r.components.push_back({"res_offsets", a_.res_offsets.size() * std::uint64_t{4},
                          "u32 per row + 1: first residual 1x1 term of the row"});
  r.components.push_back({"res_columns", a_.res_columns.size() * col_bytes,
                          col_type + " per residual term: global pixel k, increasing in a row"});
  r.components.push_back({"res_counts", a_.res_counts.size() * std::uint64_t{2},
                          "i16 per residual term: signed count (x 1/s^2)"});
  r.components.push_back({"scale", 4, "f32 once: 1/s^2 (stored as s in the metadata)"});
  return r;
}

double BiclusterTransfer::flops_per_relight() const {
  // sum (r_i + 2 l_i - 1) = incidences + 2 columns - biclusters; a residual term counts 2.
  return static_cast<double>(a_.row_bics.size()) + 2.0 * a_.bic_columns.size() -
         static_cast<double>(a_.bicluster_count()) + 2.0 * a_.res_columns.size();
}

LightCoeffs BiclusterTransfer::project_light(const Cubemap& radiance) const {
  if (radiance.layout.pixel_count() != a_.pixel_count) {
    throw ParameterError(
        fmt::format("{}: the light cubemap has N = {} pixels (R = {}), the transfer N = {}", kName,
                    radiance.layout.pixel_count(), radiance.layout.resolution(), a_.pixel_count));
  }
  return {"pixel", radiance.light_vector()};
}

void BiclusterTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  if (light.basis != "pixel" || light.values.size() != static_cast<std::size_t>(a_.pixel_count)) {
    throw ParameterError(fmt::format(
        "{}: relight needs a pixel-basis light of N = {} values, got basis '{}' with {}", kName,
        a_.pixel_count, light.basis, light.values.size()));
  }
  const std::size_t rows = a_.rows();
  if (out.basis != RadianceBasis::kPixel || out.dim != a_.local_count ||
      out.vertices != a_.vertices || out.values.size() != rows) {
    out = LocalRadiance(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  }
  // Phase 1 (Algorithm 2, lines 1-3): one RGB scalar per bicluster. Double accumulation: the
  // constants and residuals are signed, so partial sums can cancel.
  const std::size_t nb = a_.bicluster_count();
  // Each output element is summed by one task in a fixed order: the result does not depend on
  // the thread count.
  std::vector<glm::dvec3> p(nb);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 4096), [&](const auto& range) {
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      glm::dvec3 acc(0.0);
      for (std::uint32_t q = a_.bic_col_offsets[i]; q < a_.bic_col_offsets[i + 1]; ++q)
        acc +=
            static_cast<double>(a_.bic_constants[q]) * glm::dvec3(light.values[a_.bic_columns[q]]);
      p[i] = acc;
    }
  });
  // Phase 2 (lines 4-11): gather per row, plus the row's residual terms.
  const double scale = a_.scale();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 4096), [&](const auto& range) {
    for (std::size_t j = range.begin(); j < range.end(); ++j) {
      glm::dvec3 acc(0.0);
      for (std::uint32_t q = a_.row_bic_offsets[j]; q < a_.row_bic_offsets[j + 1]; ++q)
        acc += p[a_.row_bics[q]];
      for (std::uint32_t q = a_.res_offsets[j]; q < a_.res_offsets[j + 1]; ++q)
        acc += static_cast<double>(a_.res_counts[q]) * glm::dvec3(light.values[a_.res_columns[q]]);
      out.values[j] = Rgb(acc * scale);
    }
  });
}

std::unique_ptr<DeviceRelighter> BiclusterTransfer::upload(ClContext& context) const {
  return upload_arrays(context, a_);
}

namespace {
void add_columns(ArchiveWriter& w, const std::string& name, const std::vector<std::uint32_t>& c,
                 bool narrow) {
  if (narrow) {
    std::vector<std::uint16_t> c16(c.begin(), c.end());
    w.add_section(name, std::move(c16));
  } else {
    w.add_section(name, c);
  }
}

std::vector<std::uint32_t> read_columns(const ArchiveReader& r, const std::string& name) {
  if (r.section_info(name).type == ElementType::kUInt16) {
    const auto v = r.view<std::uint16_t>(name);
    return {v.begin(), v.end()};
  }
  return r.section<std::uint32_t>(name);
}
}  // namespace

void BiclusterTransfer::save(ArchiveWriter& w) const {
  w.add_meta("bicluster_version", kStateVersion);
  w.add_meta("vertices", a_.vertices);
  w.add_meta("local_count", a_.local_count);
  w.add_meta("pixel_count", a_.pixel_count);
  w.add_meta("supersampling", a_.supersampling);
  w.add_section("bic_col_offsets", a_.bic_col_offsets);
  add_columns(w, "bic_columns", a_.bic_columns, narrow());
  w.add_section("bic_constants", a_.bic_constants);
  w.add_section("row_bic_offsets", a_.row_bic_offsets);
  w.add_section("row_bics", a_.row_bics);
  w.add_section("res_offsets", a_.res_offsets);
  add_columns(w, "res_columns", a_.res_columns, narrow());
  w.add_section("res_counts", a_.res_counts);
}

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
  if (a.local_count <= 0 || a.pixel_count <= 0 || a.supersampling <= 0)
    throw InputError(r.path(), fmt::format("{}: non-positive shape in the metadata", kName));
  const std::size_t rows = a.rows();
  a.bic_col_offsets = r.section<std::uint32_t>("bic_col_offsets");
  a.bic_columns = read_columns(r, "bic_columns");
  a.bic_constants = r.section<std::int16_t>("bic_constants", a.bic_columns.size());
  a.row_bic_offsets = r.section<std::uint32_t>("row_bic_offsets", rows + 1);
  a.row_bics = r.section<std::uint32_t>("row_bics");
  a.res_offsets = r.section<std::uint32_t>("res_offsets", rows + 1);
  a.res_columns = read_columns(r, "res_columns");
  a.res_counts = r.section<std::int16_t>("res_counts", a.res_columns.size());
  auto check_offsets = [&](const std::vector<std::uint32_t>& off, std::size_t total,
                           const char* name) {
    if (off.empty() || off.front() != 0 || off.back() != total ||
        !std::is_sorted(off.begin(), off.end()))
      throw InputError(r.path(),
                       fmt::format("{}: section {} is not a valid offset array", kName, name));
  };
  check_offsets(a.bic_col_offsets, a.bic_columns.size(), "bic_col_offsets");
  check_offsets(a.row_bic_offsets, a.row_bics.size(), "row_bic_offsets");
  check_offsets(a.res_offsets, a.res_columns.size(), "res_offsets");
  const auto n = static_cast<std::uint32_t>(a.pixel_count);
  if (std::any_of(a.bic_columns.begin(), a.bic_columns.end(), [&](auto k) { return k >= n; }) ||
      std::any_of(a.res_columns.begin(), a.res_columns.end(), [&](auto k) { return k >= n; }))
    throw InputError(r.path(), fmt::format("{}: a column id is >= N = {}", kName, n));
  const std::size_t nb = a.bicluster_count();
  if (std::any_of(a.row_bics.begin(), a.row_bics.end(), [&](auto i) { return i >= nb; }))
    throw InputError(r.path(), fmt::format("{}: a bicluster id is >= {}", kName, nb));
  return std::make_unique<BiclusterTransfer>(std::move(a));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "lossless constant-column biclustering of T, two-phase relight (Sun et al., "
      "biclustering for all-frequency bi-scale PRT)";
  e.lossless = true;
  e.create = [](const ParamSet& params) -> std::unique_ptr<Compressor> {
    return std::make_unique<BiclusterCompressor>(
        static_cast<std::uint64_t>(params.get_int("seed")));
  };
  e.load = &BiclusterTransfer::load;
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::bicluster
