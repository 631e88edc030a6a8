// Encoding of backend `haar`: every row of T through the face transform, the selection of its
// terms (per row, or under a global budget), and their quantisation, with the squared errors of
// each step accumulated in double (compressors/haar/README.md, "Selection").
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "haar/haar.h"
#include "haar/haar_wavelet.h"
#include "prtlab/base/error.h"
#include "prtlab/numeric/float16.h"

namespace prt::haar {
namespace {

// Rows per task: enough work per task, and a fixed partition, so that the double sums of the
// errors (summed per chunk, then over chunks in order) do not depend on the thread count.
constexpr std::size_t kChunk = 1024;

struct Candidate {
  std::uint32_t index;
  double value;
  double score;
};

// Highest score first; ties by the lower index, so the choice is deterministic.
bool better(const Candidate& a, const Candidate& b) {
  return a.score != b.score ? a.score > b.score : a.index < b.index;
}

// The transformed non-zero coefficients of one row, in a reusable workspace.
class RowTransform {
 public:
  RowTransform(const TransferMatrix& t, int resolution, std::span<const double> omega,
               Scaling scaling)
      : t_(t),
        r_(resolution),
        face_(static_cast<std::size_t>(resolution) * resolution),
        omega_(omega),
        scaling_(scaling),
        dense_(6 * face_, 0.0),
        scratch_(face_) {}

  // The row's candidates (every non-zero coefficient with its score) and its squared norm.
  std::span<Candidate> operator()(std::size_t row, double& squared_norm) {
    std::array<bool, 6> touched{};
    squared_norm = 0;
    const auto offsets = t_.row_offsets();
    for (std::uint32_t e = offsets[row]; e < offsets[row + 1]; ++e) {
      const std::uint32_t k = t_.column(e);
      const double v = t_.counts()[e] * t_.scale();
      dense_[k] = v;
      squared_norm += v * v;
      touched[k / face_] = true;
    }
    candidates_.clear();
    for (std::size_t f = 0; f < 6; ++f) {
      if (!touched[f]) continue;
      const std::span<double> face(&dense_[f * face_], face_);
      forward_face(face, r_, scratch_);
      for (std::size_t i = 0; i < face_; ++i) {
        if (face[i] == 0.0) continue;
        const auto k = static_cast<std::uint32_t>(f * face_ + i);
        const bool forced = scaling_ == Scaling::kAlways && i == 0;
        candidates_.push_back(
            {k, face[i],
             forced ? std::numeric_limits<double>::infinity() : std::abs(face[i]) * omega_[k]});
      }
      std::fill(face.begin(), face.end(), 0.0);
    }
    return candidates_;
  }

 private:
  const TransferMatrix& t_;
  int r_;
  std::size_t face_;
  std::span<const double> omega_;
  Scaling scaling_;
  std::vector<double> dense_, scratch_;
  std::vector<Candidate> candidates_;
};

// Moves the best `keep` candidates to the front, sorted by index.
void select_best(std::span<Candidate> c, std::size_t keep) {
  keep = std::min(keep, c.size());
  if (keep < c.size()) std::nth_element(c.begin(), c.begin() + keep, c.end(), better);
  std::sort(c.begin(), c.begin() + keep,
            [](const Candidate& a, const Candidate& b) { return a.index < b.index; });
}

// One chunk of rows, encoded.
struct Chunk {
  std::vector<std::uint32_t> counts, indices;
  std::vector<double> values;  // before quantisation
  double truncation = 0, norm = 0;
};

// The global budget's per-row term counts: the k x rows best scores of the whole matrix (each
// row's best max_terms only), ties among equal scores given in row order.
std::vector<std::uint32_t> global_counts(const TransferMatrix& t, int resolution,
                                         std::span<const double> omega, const HaarOptions& o,
                                         std::size_t max_terms, Progress& progress) {
  const std::size_t rows = t.rows();
  const std::size_t chunks = (rows + kChunk - 1) / kChunk;
  std::vector<std::vector<float>> best(rows);  // descending, at most max_terms per row
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    RowTransform transform(t, resolution, omega, o.scaling);
    double norm = 0;
    for (std::size_t row = c * kChunk; row < std::min(rows, (c + 1) * kChunk); ++row) {
      std::span<Candidate> cand = transform(row, norm);
      const std::size_t keep = std::min(max_terms, cand.size());
      std::partial_sort(cand.begin(), cand.begin() + keep, cand.end(), better);
      best[row].resize(keep);
      for (std::size_t i = 0; i < keep; ++i)
        best[row][i] = static_cast<float>(std::min(cand[i].score, 1e30));
    }
    progress.advance(static_cast<std::int64_t>(std::min(rows, (c + 1) * kChunk) - c * kChunk));
  });
  std::vector<float> all;
  for (const auto& b : best) all.insert(all.end(), b.begin(), b.end());
  const std::size_t budget = std::min(all.size(), static_cast<std::size_t>(o.k) * rows);
  std::vector<std::uint32_t> counts(rows, 0);
  if (budget == 0) return counts;
  std::nth_element(all.begin(), all.begin() + (budget - 1), all.end(), std::greater<>());
  const float threshold = all[budget - 1];
  std::size_t taken = 0;
  for (std::size_t row = 0; row < rows; ++row) {
    const auto& b = best[row];
    // Strictly better than the threshold first; ties below.
    counts[row] = static_cast<std::uint32_t>(
        std::lower_bound(b.begin(), b.end(), threshold, std::greater<>()) - b.begin());
    taken += counts[row];
  }
  for (std::size_t row = 0; row < rows && taken < budget; ++row) {
    const auto& b = best[row];
    while (counts[row] < b.size() && b[counts[row]] == threshold && taken < budget) {
      ++counts[row];
      ++taken;
    }
  }
  return counts;
}

}  // namespace

HaarArrays encode_haar(const TransferMatrix& t, const CubemapLayout& cubemap, const HaarOptions& o,
                       Progress& progress) {
  const int r = cubemap.resolution();
  const std::vector<double> omega = support_solid_angles(cubemap);  // checks R
  PRT_CHECK(t.cols() == static_cast<std::size_t>(cubemap.pixel_count()),
            "haar: T has {} columns, the cubemap N = {}", t.cols(), cubemap.pixel_count());
  if (o.k < 1) throw ParameterError(fmt::format("{}: k = {} is not at least 1", kName, o.k));
  const std::size_t rows = t.rows();
  const std::size_t n = t.cols();
  const std::size_t max_terms = std::min(n, o.max_terms > 0 ? static_cast<std::size_t>(o.max_terms)
                                                            : 8 * static_cast<std::size_t>(o.k));

  std::vector<std::uint32_t> counts;
  if (o.budget == Budget::kGlobal) counts = global_counts(t, r, omega, o, max_terms, progress);

  const std::size_t chunks = (rows + kChunk - 1) / kChunk;
  std::vector<Chunk> parts(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    RowTransform transform(t, r, omega, o.scaling);
    Chunk& part = parts[c];
    const std::size_t end = std::min(rows, (c + 1) * kChunk);
    for (std::size_t row = c * kChunk; row < end; ++row) {
      double norm = 0;
      std::span<Candidate> cand = transform(row, norm);
      const std::size_t keep = o.budget == Budget::kGlobal
                                   ? counts[row]
                                   : std::min(cand.size(), static_cast<std::size_t>(o.k));
      select_best(cand, keep);
      part.counts.push_back(static_cast<std::uint32_t>(keep));
      for (std::size_t i = 0; i < keep; ++i) {
        part.indices.push_back(cand[i].index);
        part.values.push_back(cand[i].value);
      }
      for (std::size_t i = keep; i < cand.size(); ++i)
        part.truncation += cand[i].value * cand[i].value;
      part.norm += norm;
    }
    if (o.budget == Budget::kPerRow) progress.advance(static_cast<std::int64_t>(end - c * kChunk));
  });

  HaarArrays a;
  a.vertices = t.vertex_count();
  a.local_count = t.local_count();
  a.pixel_count = static_cast<int>(n);
  a.resolution = r;
  a.format = o.format;
  a.budget = o.budget;
  a.scaling = o.scaling;
  a.k = o.k;
  a.wide = o.wide_index || n > 65536;
  a.offsets.assign(1, 0);
  a.offsets.reserve(rows + 1);
  std::vector<std::uint32_t> indices;
  std::vector<double> values;
  for (const Chunk& part : parts) {
    for (std::uint32_t count : part.counts) {
      if (a.offsets.back() > std::numeric_limits<std::uint32_t>::max() - count)
        throw ParameterError(
            fmt::format("{}: more than 2^32 - 1 kept terms (u32 row offsets)", kName));
      a.offsets.push_back(a.offsets.back() + count);
    }
    indices.insert(indices.end(), part.indices.begin(), part.indices.end());
    values.insert(values.end(), part.values.begin(), part.values.end());
    a.truncation_squared_error += part.truncation;
    a.total_squared_norm += part.norm;
  }
  if (a.wide) {
    a.indices32 = std::move(indices);
  } else {
    a.indices16.assign(indices.begin(), indices.end());
  }

  // Quantisation, row by row (s8 needs the row's largest magnitude).
  double quantization = 0;
  const std::size_t terms = values.size();
  switch (o.format) {
    case ValueFormat::kFloat32:
      a.values32.resize(terms);
      for (std::size_t i = 0; i < terms; ++i) {
        a.values32[i] = static_cast<float>(values[i]);
        quantization += std::pow(a.values32[i] - values[i], 2);
      }
      break;
    case ValueFormat::kFloat16:
      a.values16.resize(terms);
      for (std::size_t i = 0; i < terms; ++i) {
        a.values16[i] = float_to_half(static_cast<float>(values[i]));
        const double v = half_to_float(a.values16[i]);
        if (!std::isfinite(v))
          throw ParameterError(
              fmt::format("{}: coefficient {} does not fit an IEEE half (use values=float32)",
                          kName, values[i]));
        quantization += std::pow(v - values[i], 2);
      }
      break;
    case ValueFormat::kS8:
      a.codes.resize(terms);
      a.row_scales.assign(rows, 0.f);
      for (std::size_t row = 0; row < rows; ++row) {
        double peak = 0;
        for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i)
          peak = std::max(peak, std::abs(values[i]));
        const float scale = static_cast<float>(peak / 127.0);
        a.row_scales[row] = scale;
        for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i) {
          const double code =
              scale > 0 ? std::clamp(std::nearbyint(values[i] / scale), -127.0, 127.0) : 0.0;
          a.codes[i] = static_cast<std::int8_t>(code);
          quantization += std::pow(code * static_cast<double>(scale) - values[i], 2);
        }
      }
      break;
  }
  a.quantization_squared_error = quantization;
  progress.finish();
  return a;
}

double HaarArrays::frobenius_error() const {
  if (total_squared_norm <= 0) return 0.0;
  return std::sqrt((truncation_squared_error + quantization_squared_error) / total_squared_norm);
}

std::size_t HaarArrays::value_bytes() const {
  return format == ValueFormat::kFloat32 ? 4 : (format == ValueFormat::kFloat16 ? 2 : 1);
}

std::size_t HaarArrays::count_bytes() const {
  std::uint32_t most = 0;
  for (std::size_t row = 0; row < rows(); ++row) most = std::max(most, count(row));
  return most <= 0xffu ? 1 : (most <= 0xffffu ? 2 : 4);
}

}  // namespace prt::haar
