#include "prtlab/sphere/hemisphere_projection.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"

namespace prt {

namespace {

void check_order(int order, const char* what) {
  if (order < 1 || order > kMaxShOrder) {
    throw ParameterError(
        fmt::format("{}: SH order must be in [1, {}], got {}", what, kMaxShOrder, order));
  }
}

void check_zone(double z_min, double z_max, const char* what) {
  if (!(z_min >= -1.0 && z_min < z_max && z_max <= 1.0)) {
    throw ParameterError(fmt::format(
        "{}: zone z in [{}, {}] is not inside -1 <= z_min < z_max <= 1", what, z_min, z_max));
  }
}

// The phi integral of Phi_m^2: 2 pi for m = 0, pi for cos^2(m phi) and sin^2(m phi).
double phi_weight(int m) {
  return m == 0 ? kTwoPi : kPi;
}

// The square roots of A's blocks over a zone: factor[a] (a = |m|) has one row per Gauss node z_j
// and one column per l = a .. order - 1, entry sqrt(w_a W_j) T_l^a(z_j). Then the block of m and
// of -m is factor[|m|]^T factor[|m|] exactly (the rule integrates the degree <= 2 order - 2
// products exactly with `order` nodes).
std::vector<Eigen::MatrixXd> zone_factors(int order, double z_min, double z_max) {
  const GaussLegendreRule rule = gauss_legendre(order, z_min, z_max);
  std::vector<Eigen::MatrixXd> factor(order);
  for (int a = 0; a < order; ++a) factor[a].resize(order, order - a);
  std::array<double, sh_count(kMaxShOrder)> y{};
  for (int j = 0; j < order; ++j) {
    const double z = rule.nodes[j];
    // At phi = 0, y_l,m = T_l^m(z) for m >= 0 (cos(0) = 1): sh_eval gives the z-parts with
    // exactly the library's normalisation.
    sh_eval(order, {std::sqrt((1.0 - z) * (1.0 + z)), 0.0, z}, y);
    for (int a = 0; a < order; ++a) {
      const double s = std::sqrt(phi_weight(a) * rule.weights[j]);
      for (int l = a; l < order; ++l) factor[a](j, l - a) = s * y[sh_index(l, a)];
    }
  }
  return factor;
}

// SH indices of the block of m, in increasing l.
std::vector<int> block_indices(int order, int m) {
  std::vector<int> idx;
  for (int l = std::abs(m); l < order; ++l) idx.push_back(sh_index(l, m));
  return idx;
}

// Coefficients (increasing powers) of d^k/dz^k (z^2 - 1)^l, exact in int64 for l <= 9 and
// k <= 18: the largest is C(9, 4) 18! / 0! < 2^63 / 11.
std::vector<std::int64_t> rodrigues_derivative(int l, int k) {
  std::vector<std::int64_t> c(2 * l + 1, 0);
  std::int64_t binom = 1;  // C(l, i)
  for (int i = 0; i <= l; ++i) {
    c[2 * i] = ((l - i) % 2 == 0 ? 1 : -1) * binom;
    binom = binom * (l - i) / (i + 1);
  }
  for (int t = 0; t < k; ++t) {
    for (std::size_t p = 1; p < c.size(); ++p) c[p - 1] = c[p] * static_cast<std::int64_t>(p);
    c.back() = 0;
  }
  return c;
}
static_assert(kMaxShOrder <= 10, "rodrigues_derivative's int64 range assumes l <= 9");

using LongPoly = std::vector<long double>;

LongPoly multiply(const LongPoly& a, const LongPoly& b) {
  LongPoly r(a.size() + b.size() - 1, 0.0L);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

}  // namespace

Eigen::MatrixXd sh_zone_gram(int order, double z_min, double z_max) {
  check_order(order, "sh_zone_gram");
  check_zone(z_min, z_max, "sh_zone_gram");
  const auto factor = zone_factors(order, z_min, z_max);
  const int n = sh_count(order);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int m = -(order - 1); m < order; ++m) {
    const std::vector<int> idx = block_indices(order, m);
    const Eigen::MatrixXd& f = factor[std::abs(m)];
    const Eigen::MatrixXd block = f.transpose() * f;
    // The upper triangle, mirrored: exactly symmetric, whatever the product's summation order.
    for (std::size_t p = 0; p < idx.size(); ++p) {
      for (std::size_t q = p; q < idx.size(); ++q) {
        a(idx[p], idx[q]) = block(p, q);
        a(idx[q], idx[p]) = block(p, q);
      }
    }
  }
  return a;
}

Eigen::MatrixXd hemisphere_gram(int order) {
  return sh_zone_gram(order, 0.0, 1.0);
}

// y_lm = sqrt(2) K_l^a P_l^a Phi_m (a = |m| > 0) or K_l^0 P_l^0, and P_l^a(z) =
// (1 - z^2)^(a/2) d^a/dz^a P_l(z) with P_l = d^l/dz^l (z^2 - 1)^l / (2^l l!) (Rodrigues). The
// sqrt(2)^2 pi of m != 0 equals the 2 pi of m = 0, so every block entry is
//   2 pi K_l^a K_l'^a / (2^l l! 2^l' l'!) integral (1 - z^2)^a R_l R_l' dz,
// R_l = d^(l+a)/dz^(l+a) (z^2 - 1)^l.
Eigen::MatrixXd sh_zone_gram_closed_form(int order, double z_min, double z_max) {
  check_order(order, "sh_zone_gram_closed_form");
  check_zone(z_min, z_max, "sh_zone_gram_closed_form");
  const long double pi = 3.141592653589793238462643383279502884L;
  auto factorial = [](int k) {
    long double f = 1.0L;
    for (int i = 2; i <= k; ++i) f *= i;
    return f;
  };
  const int n = sh_count(order);
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  for (int a = 0; a < order; ++a) {
    LongPoly weight{1.0L};  // (1 - z^2)^a
    for (int i = 0; i < a; ++i) weight = multiply(weight, {1.0L, 0.0L, -1.0L});
    // The scaled polynomials s_l R_l (1 - z^2)^(a/2) with s_l = K_l^a / (2^l l!).
    std::vector<LongPoly> r(order);
    std::vector<long double> scale(order, 0.0L);
    for (int l = a; l < order; ++l) {
      const auto c = rodrigues_derivative(l, l + a);
      r[l].assign(c.begin(), c.end());
      const long double k2 = (2.0L * l + 1.0L) / (4.0L * pi) * factorial(l - a) / factorial(l + a);
      scale[l] = std::sqrt(k2) / (std::pow(2.0L, l) * factorial(l));
    }
    for (int l = a; l < order; ++l) {
      const LongPoly wl = multiply(weight, r[l]);
      for (int lp = l; lp < order; ++lp) {
        const LongPoly p = multiply(wl, r[lp]);
        long double integral = 0.0L;
        long double zb = z_max, za = z_min;  // z^(k+1) at the two ends
        for (std::size_t k = 0; k < p.size(); ++k) {
          integral += p[k] * (zb - za) / static_cast<long double>(k + 1);
          zb *= z_max;
          za *= z_min;
        }
        const double v = static_cast<double>(2.0L * pi * scale[l] * scale[lp] * integral);
        for (int m : {a, -a}) {
          out(sh_index(l, m), sh_index(lp, m)) = v;
          out(sh_index(lp, m), sh_index(l, m)) = v;
        }
      }
    }
  }
  return out;
}

Eigen::MatrixXd sh_gram(int order, std::span<const SphereQuadratureNode> nodes) {
  check_order(order, "sh_gram");
  const int n = sh_count(order);
  // Blocks of nodes through one matrix product each: fast, and a fixed summation order.
  constexpr int kChunk = 512;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd y(kChunk, n);
  std::array<double, sh_count(kMaxShOrder)> v{};
  for (std::size_t start = 0; start < nodes.size(); start += kChunk) {
    const int rows = static_cast<int>(std::min<std::size_t>(kChunk, nodes.size() - start));
    for (int r = 0; r < rows; ++r) {
      const SphereQuadratureNode& node = nodes[start + r];
      sh_eval(order, node.direction, v);
      const double s = std::sqrt(node.weight);
      for (int i = 0; i < n; ++i) y(r, i) = s * v[i];
    }
    a.noalias() += y.topRows(rows).transpose() * y.topRows(rows);
  }
  return a;
}

double sh_gram_midpoint_error_bound(int order, double z_min, double z_max, int z_cells) {
  check_order(order, "sh_gram_midpoint_error_bound");
  check_zone(z_min, z_max, "sh_gram_midpoint_error_bound");
  if (z_cells < 1) throw ParameterError("sh_gram_midpoint_error_bound: z_cells must be >= 1");
  const double length = z_max - z_min;
  const double h = length / z_cells;
  const double d = 2.0 * (order - 1);
  const double max_g = kTwoPi * (2.0 * order - 1.0) / kFourPi;
  const double max_g2 = 4.0 * d * d * (d - 1.0) * (d - 1.0) * max_g / (length * length);
  return h * h / 24.0 * length * std::max(0.0, max_g2);
}

Eigen::VectorXd sh_quadrature_projection(int order, std::span<const SphereQuadratureNode> nodes,
                                         const std::function<double(const Vec3d&)>& f) {
  check_order(order, "sh_quadrature_projection");
  const int n = sh_count(order);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  std::array<double, sh_count(kMaxShOrder)> y{};
  for (const SphereQuadratureNode& node : nodes) {
    const double wf = node.weight * f(node.direction);
    if (wf == 0.0) continue;
    sh_eval(order, node.direction, y);
    for (int i = 0; i < n; ++i) b[i] += wf * y[i];
  }
  return b;
}

HemisphereProjector::HemisphereProjector(int order, const HemisphereProjectorOptions& options)
    : order_(order) {
  check_order(order, "HemisphereProjector");
  if (!(options.relative_cutoff >= 0.0 && options.relative_cutoff < 1.0)) {
    throw ParameterError(fmt::format(
        "HemisphereProjector: relative_cutoff must be in [0, 1), got {}", options.relative_cutoff));
  }
  if (options.dropped_index < -1 || options.dropped_index >= sh_count(order)) {
    throw ParameterError(
        fmt::format("HemisphereProjector: dropped_index must be -1 or an SH index below {}, got {}",
                    sh_count(order), options.dropped_index));
  }
  const auto factor = zone_factors(order, 0.0, 1.0);
  struct Decomposed {
    std::vector<int> indices;
    Eigen::MatrixXd v;
    Eigen::VectorXd s2;
  };
  std::vector<Decomposed> all;
  for (int m = -(order - 1); m < order; ++m) {
    std::vector<int> idx = block_indices(order, m);
    Eigen::MatrixXd f = factor[std::abs(m)];
    const auto drop = std::find(idx.begin(), idx.end(), options.dropped_index);
    if (drop != idx.end()) {
      const int col = static_cast<int>(drop - idx.begin());
      Eigen::MatrixXd reduced(f.rows(), f.cols() - 1);
      reduced << f.leftCols(col), f.rightCols(f.cols() - col - 1);
      f = reduced;
      idx.erase(drop);
    }
    if (idx.empty()) continue;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(f, Eigen::ComputeThinV);
    all.push_back({idx, svd.matrixV(), svd.singularValues().array().square()});
    lambda_max_ = std::max(lambda_max_, all.back().s2.maxCoeff());
  }
  const double threshold = options.relative_cutoff * lambda_max_;
  lambda_kept_min_ = std::numeric_limits<double>::infinity();
  for (const Decomposed& d : all) {
    Block b;
    b.indices = d.indices;
    std::vector<int> kept;
    for (int j = 0; j < d.s2.size(); ++j) {
      if (d.s2[j] > threshold) {
        kept.push_back(j);
        lambda_kept_min_ = std::min(lambda_kept_min_, d.s2[j]);
      } else {
        ++cut_;
        lambda_cut_max_ = std::max(lambda_cut_max_, d.s2[j]);
      }
    }
    b.vectors.resize(d.v.rows(), static_cast<Eigen::Index>(kept.size()));
    b.inverse_eigenvalues.resize(static_cast<Eigen::Index>(kept.size()));
    for (std::size_t k = 0; k < kept.size(); ++k) {
      b.vectors.col(k) = d.v.col(kept[k]);
      b.inverse_eigenvalues[k] = 1.0 / d.s2[kept[k]];
    }
    blocks_.push_back(std::move(b));
  }
}

Eigen::VectorXd HemisphereProjector::solve(const Eigen::VectorXd& b) const {
  if (b.size() != size()) {
    throw ParameterError(
        fmt::format("HemisphereProjector::solve: b has {} entries, order {} needs {}", b.size(),
                    order_, size()));
  }
  Eigen::VectorXd c = Eigen::VectorXd::Zero(size());
  for (const Block& block : blocks_) {
    Eigen::VectorXd bm(static_cast<Eigen::Index>(block.indices.size()));
    for (std::size_t p = 0; p < block.indices.size(); ++p) bm[p] = b[block.indices[p]];
    const Eigen::VectorXd t =
        (block.vectors.transpose() * bm).cwiseProduct(block.inverse_eigenvalues);
    const Eigen::VectorXd cm = block.vectors * t;
    for (std::size_t p = 0; p < block.indices.size(); ++p) c[block.indices[p]] = cm[p];
  }
  return c;
}

Eigen::VectorXd hemisphere_gram_eigenvalues(int order) {
  check_order(order, "hemisphere_gram_eigenvalues");
  const auto factor = zone_factors(order, 0.0, 1.0);
  std::vector<double> values;
  for (int a = 0; a < order; ++a) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(factor[a]);
    for (int j = 0; j < svd.singularValues().size(); ++j) {
      const double s = svd.singularValues()[j];
      values.push_back(s * s);
      if (a > 0) values.push_back(s * s);
    }
  }
  std::sort(values.begin(), values.end(), std::greater<>());
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

// (A^-1)_ii^-1 is the squared distance of column i of F from the span of the other columns of
// the block (the other functions of the same m; the other blocks are orthogonal to it on H),
// which is the last diagonal entry of R, squared, once that column is ordered last.
Eigen::VectorXd hemisphere_discard_errors(int order) {
  check_order(order, "hemisphere_discard_errors");
  const auto factor = zone_factors(order, 0.0, 1.0);
  Eigen::VectorXd e(sh_count(order));
  for (int a = 0; a < order; ++a) {
    const Eigen::MatrixXd& f = factor[a];
    const int cols = static_cast<int>(f.cols());
    for (int col = 0; col < cols; ++col) {
      Eigen::MatrixXd permuted(f.rows(), cols);
      int next = 0;
      for (int k = 0; k < cols; ++k)
        if (k != col) permuted.col(next++) = f.col(k);
      permuted.col(cols - 1) = f.col(col);
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(permuted);
      const double r = qr.matrixQR()(cols - 1, cols - 1);
      const int l = a + col;
      e[sh_index(l, a)] = r * r;
      e[sh_index(l, -a)] = r * r;
    }
  }
  return e;
}

std::string_view to_string(HemisphereProjectionKind kind) {
  switch (kind) {
    case HemisphereProjectionKind::kZeroHemisphere:
      return "zero_hemisphere";
    case HemisphereProjectionKind::kOddReflection:
      return "odd_reflection";
    case HemisphereProjectionKind::kEvenReflection:
      return "even_reflection";
  }
  return "unknown";
}

Eigen::VectorXd reflection_scale(HemisphereProjectionKind kind, int order) {
  check_order(order, "reflection_scale");
  Eigen::VectorXd d(sh_count(order));
  for (int l = 0; l < order; ++l) {
    for (int m = -l; m <= l; ++m) {
      const bool odd_in_z = (l + m) % 2 != 0;
      double s = 1.0;
      if (kind == HemisphereProjectionKind::kOddReflection) s = odd_in_z ? 2.0 : 0.0;
      if (kind == HemisphereProjectionKind::kEvenReflection) s = odd_in_z ? 0.0 : 2.0;
      d[sh_index(l, m)] = s;
    }
  }
  return d;
}

Eigen::MatrixXd hemisphere_projection_error_matrix(HemisphereProjectionKind kind, int signal_order,
                                                   int projection_order) {
  check_order(signal_order, "hemisphere_projection_error_matrix");
  check_order(projection_order, "hemisphere_projection_error_matrix");
  if (projection_order < signal_order) {
    throw ParameterError(fmt::format(
        "hemisphere_projection_error_matrix: {} projection order {} is below the signal order {}",
        to_string(kind), projection_order, signal_order));
  }
  const int n = sh_count(signal_order);
  const Eigen::MatrixXd a = hemisphere_gram(projection_order);
  const Eigen::VectorXd d = reflection_scale(kind, projection_order);
  // Only the first n columns of D* A - I meet a padded c.
  Eigen::MatrixXd b = d.asDiagonal() * a.leftCols(n);
  b.topRows(n) -= Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd q = b.transpose() * a * b;
  return 0.5 * (q + q.transpose());
}

double HemisphereProjectionError::worst_rms_percent() const {
  return 100.0 * std::sqrt(worst);
}
double HemisphereProjectionError::average_rms_percent() const {
  return 100.0 * std::sqrt(average);
}

HemisphereProjectionError hemisphere_projection_error(HemisphereProjectionKind kind,
                                                      int signal_order, int projection_order) {
  const Eigen::MatrixXd q =
      hemisphere_projection_error_matrix(kind, signal_order, projection_order);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(q, Eigen::EigenvaluesOnly);
  HemisphereProjectionError e;
  e.kind = kind;
  e.signal_order = signal_order;
  e.projection_order = projection_order;
  e.coefficients =
      static_cast<int>((reflection_scale(kind, projection_order).array() != 0.0).count());
  e.worst = eig.eigenvalues().maxCoeff();
  e.average = q.trace() / static_cast<double>(q.rows());
  return e;
}

HemisphereAnalysis analyse_hemisphere_projection(int order,
                                                 const HemisphereAnalysisOptions& options) {
  check_order(order, "analyse_hemisphere_projection");
  auto resolve = [order](const std::optional<int>& given, int paper, const char* name) {
    if (!given) return std::max(paper, order);
    if (*given < order || *given > kMaxShOrder) {
      throw ParameterError(fmt::format(
          "hemisphere analysis: the {} reflection order must be in [{}, {}] (at least the signal "
          "order {}), got {}",
          name, order, kMaxShOrder, order, *given));
    }
    return *given;
  };
  const int odd = resolve(options.odd_order, kPaperOddReflectionOrder, "odd");
  const int even = resolve(options.even_order, kPaperEvenReflectionOrder, "even");
  HemisphereAnalysis out;
  out.order = order;
  out.eigenvalues = hemisphere_gram_eigenvalues(order);
  out.discard_error = hemisphere_discard_errors(order);
  Eigen::Index most = 0;
  out.discard_error.minCoeff(&most);
  out.most_redundant = static_cast<int>(most);
  out.projections = {
      hemisphere_projection_error(HemisphereProjectionKind::kZeroHemisphere, order, order),
      hemisphere_projection_error(HemisphereProjectionKind::kOddReflection, order, odd),
      hemisphere_projection_error(HemisphereProjectionKind::kEvenReflection, order, even),
      hemisphere_projection_error(HemisphereProjectionKind::kEvenReflection, order, order)};
  return out;
}

}  // namespace prt
