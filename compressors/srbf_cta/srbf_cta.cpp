// The srbf_cta compressor: T's rows onto the transfer SRBFs, the tensor through clustered tensor
// approximation, the model encoded and its pixel-basis error measured; and the registry entry.
#include "srbf_cta/srbf_cta.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>

#include "prtlab/base/deterministic_reduce.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/compress/brdf_signal.h"
#include "prtlab/distributed/communicator.h"
#include "prtlab/lighting/srbf_light.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/sphere/icosphere.h"
#include "prtlab/transfer/brdf_weighted_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "srbf_cta/clustered_tensor.h"
#include "srbf_cta/cta_checkpoint.h"

namespace prt::srbf_cta {
namespace {

constexpr double kIllConditionedGram = 1e10;
/// The CTA saves its state for a resumed run at most this often.
constexpr double kCheckpointSeconds = 30.0;

using Clock = std::chrono::steady_clock;
using MatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Params {
  int srbfs = 642;
  double spread = 1.0;
  double ridge = 1e-6;
  CtaOptions cta;
  Precision precision = Precision::kFloat16;
  LightMode light = LightMode::kUniform;
  int light_srbfs = 0;
  int light_rounds = 40;
  Signal signal = Signal::kCells;
  int brdf_terms = 16;
  CookTorrance brdf;
};

/// G (N x n_t, no solid angle): t~(d_k) = (G c)_k.
Eigen::MatrixXd pixel_values(const SrbfProjector& p, const CubemapLayout& layout) {
  Eigen::MatrixXd g = p.pixel_weights();
  for (Eigen::Index k = 0; k < g.rows(); ++k) g.row(k) /= layout.solid_angle(static_cast<int>(k));
  return g;
}

/// <G c, t> for a row t of T and SRBF coefficients c: G^T t accumulated over the row's stored
/// entries, then one dot product with c in double. With G the pixel values of the SRBFs
/// (non-negative, as T is) G^T is held in float: every non-zero reads one column, and the float
/// matrix for all N pixels is half the memory traffic of the double one, which is what this loop
/// is bound by. A light operator with entries of both signs (the stored model's, which solves
/// the light fit) keeps double, where float sums could cancel.
template <class Scalar>
class CrossTerm {
 public:
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  explicit CrossTerm(const Eigen::MatrixXd& g) : gt_(g.transpose().cast<Scalar>()) {}

  const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& gt() const { return gt_; }

  double operator()(const TransferMatrix& t, std::size_t row, const float* c, Vector& q) const {
    q.setZero(gt_.rows());
    for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
      q += static_cast<Scalar>(t.value(e)) * gt_.col(t.column(e));
    return q.template cast<double>().dot(
        Eigen::Map<const Eigen::VectorXf>(c, gt_.rows()).cast<double>());
  }

 private:
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> gt_;  ///< n_t x N
};

struct Projection {
  std::vector<float> coefficients;  // rows x n_t: the tensor, vertex after vertex
  double frobenius_error = 0;       // of the SRBF representation alone
  double seconds = 0;
};

Projection project_rows(const TransferMatrix& t, const SrbfProjector& p,
                        const CubemapLayout& layout, Progress& progress, std::int64_t budget) {
  const auto t0 = Clock::now();
  const auto n = static_cast<Eigen::Index>(p.basis().size());
  // The projection is linear in a row t: c = S t with S = (A + alpha I)^-1 W^T. With many more
  // rows than pixels (a scene: 210 K rows of 6,144 pixels on the bunny) S is solved once for the
  // N pixels instead of once per row (n_t^2 per row), and P c = (P S) t gives the error's
  // ||G c||^2 term: each costs n_t per non-zero of the row. Otherwise (few rows over many
  // pixels) blocks of rows are solved as they come.
  const Eigen::MatrixXd g = pixel_values(p, layout);
  const Eigen::MatrixXd gt = g.transpose();
  const CrossTerm<float> cross(g);
  const auto pixels = static_cast<std::size_t>(g.rows());
  const bool per_pixel = t.rows() >= 2 * pixels;
  Eigen::MatrixXd wt;
  // Per pixel: S and P S in float, column-major, so a non-zero reads two contiguous n_t-float
  // columns. The products per row stream these columns from memory; in float the pair for all N
  // pixels fits a last-level cache that the double pair overflows.
  Eigen::MatrixXf s, ps;
  MatF pf;
  if (per_pixel) {
    const Eigen::MatrixXd sd = p.solve(p.pixel_weights().transpose());  // n_t x N
    s = sd.cast<float>();
    ps = ((gt * g) * sd).cast<float>();  // n_t x N
  } else {
    wt = p.pixel_weights().transpose();  // n_t x N: b's columns
    pf = (gt * g).cast<float>();         // P = G^T G
  }
  Projection out;
  out.coefficients.assign(t.rows() * static_cast<std::size_t>(n), 0.0f);
  constexpr std::size_t kBlock = 1024;
  const std::size_t blocks = (t.rows() + kBlock - 1) / kBlock;
  std::atomic<std::size_t> done{0};
  std::int64_t reported = 0;
  std::mutex progress_mutex;
  const double srbf_sq =
      deterministic_sum(blocks, 1, [&](std::size_t blk_begin, std::size_t blk_end) {
        double acc = 0;
        Eigen::VectorXf q(n);
        for (std::size_t blk = blk_begin; blk != blk_end; ++blk) {
          const std::size_t r0 = blk * kBlock, r1 = std::min(t.rows(), r0 + kBlock);
          Eigen::Map<MatF> dst(out.coefficients.data() + r0 * static_cast<std::size_t>(n),
                               static_cast<Eigen::Index>(r1 - r0), n);
          if (!per_pixel) {
            Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(r1 - r0));
            for (std::size_t row = r0; row < r1; ++row)
              for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
                b.col(static_cast<Eigen::Index>(row - r0)) +=
                    static_cast<double>(t.value(e)) * wt.col(t.column(e));
            dst = p.solve(b).transpose().cast<float>();
            const MatF cp = dst * pf;
            for (std::size_t row = r0; row < r1; ++row) {
              const auto i = static_cast<Eigen::Index>(row - r0);
              acc += static_cast<double>(cp.row(i).dot(dst.row(i))) -
                     2.0 * cross(t, row, dst.row(i).data(), q);
            }
          }
          Eigen::VectorXf c(n), pc(n);
          for (std::size_t row = r0; per_pixel && row < r1; ++row) {
            c.setZero();
            pc.setZero();
            q.setZero();
            for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e) {
              const float v = t.value(e);
              c += v * s.col(t.column(e));
              pc += v * ps.col(t.column(e));
              q += v * cross.gt().col(t.column(e));
            }
            const auto i = static_cast<Eigen::Index>(row - r0);
            dst.row(i) = c.transpose();
            // ||G c - t||^2 - ||t||^2 with the stored (float) c in the cross term and in one
            // factor of the quadratic one: P c_stored and P c differ by rounding only.
            acc += (pc.cast<double>() - 2.0 * q.cast<double>())
                       .dot(dst.row(i).transpose().cast<double>());
          }
          const std::size_t now = ++done;
          std::lock_guard lock(progress_mutex);
          const auto target = static_cast<std::int64_t>(budget * now / blocks);
          progress.advance(target - reported);
          reported = target;
        }
        return acc;
      });
  double t_sq = 0;
  for (std::size_t e = 0; e < t.nnz(); ++e) t_sq += static_cast<double>(t.value(e)) * t.value(e);
  out.frobenius_error = t_sq > 0 ? std::sqrt(std::max(0.0, srbf_sq + t_sq) / t_sq) : 0.0;
  out.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

/// The K x n_t coefficients Psi X_x of every vertex's folded rows, without the M-row tensor: the
/// projection is linear, so folding the right-hand sides first (B_x Psi^T) and solving for K
/// instead of M columns a vertex gives the same coefficients at a K / M share of the solve.
std::vector<float> project_folded(const TransferMatrix& t, const SrbfProjector& p,
                                  const Eigen::MatrixXd& psi, Progress& progress,
                                  std::int64_t budget) {
  const auto n = static_cast<Eigen::Index>(p.basis().size());
  const Eigen::MatrixXd wt = p.pixel_weights().transpose();  // n_t x N: b's columns
  const auto m = static_cast<std::size_t>(t.local_count());
  const Eigen::Index k = psi.rows();
  const Eigen::MatrixXd psi_t = psi.transpose();  // M x K
  std::vector<float> out(t.vertex_count() * static_cast<std::size_t>(k * n));
  const std::size_t per_block = std::max<std::size_t>(1, 1024 / m);
  const std::size_t blocks = (t.vertex_count() + per_block - 1) / per_block;
  std::atomic<std::size_t> done{0};
  std::int64_t reported = 0;
  std::mutex progress_mutex;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const auto& r) {
    for (std::size_t blk = r.begin(); blk != r.end(); ++blk) {
      const std::size_t x0 = blk * per_block, x1 = std::min(t.vertex_count(), x0 + per_block);
      Eigen::MatrixXd bf(n, static_cast<Eigen::Index>((x1 - x0) * static_cast<std::size_t>(k)));
      Eigen::MatrixXd b(n, static_cast<Eigen::Index>(m));
      for (std::size_t x = x0; x < x1; ++x) {
        b.setZero();
        for (std::size_t j = 0; j < m; ++j)
          for (std::uint32_t e = t.row_offsets()[x * m + j]; e < t.row_offsets()[x * m + j + 1];
               ++e)
            b.col(static_cast<Eigen::Index>(j)) +=
                static_cast<double>(t.value(e)) * wt.col(t.column(e));
        bf.middleCols(static_cast<Eigen::Index>(x - x0) * k, k).noalias() = b * psi_t;
      }
      const Eigen::MatrixXd c = p.solve(bf);  // n_t x (vertices K)
      Eigen::Map<MatF>(out.data() + x0 * static_cast<std::size_t>(k * n), c.cols(), n) =
          c.transpose().cast<float>();
      const std::size_t now = ++done;
      std::lock_guard lock(progress_mutex);
      const auto target = static_cast<std::int64_t>(budget * now / blocks);
      progress.advance(target - reported);
      reported = target;
    }
  });
  return out;
}

float encode_value(float v, Precision p, const char* what) {
  if (p == Precision::kFloat32) return v;
  if (!(std::abs(v) <= 65504.0f))
    throw ParameterError(fmt::format(
        "{}: a {} value {} does not fit an IEEE half (|v| <= 65504); use precision=float32", kName,
        what, v));
  return half_to_float(float_to_half(v));
}

/// `view`: the stored view basis (M x R1): the model's U for cells, Phi U for the BRDF signal.
SrbfCtaArrays encode(const CtaModel& m, const Eigen::MatrixXd& view, const Params& p,
                     const TransferMatrix& t, double bandwidth) {
  SrbfCtaArrays a;
  a.vertices = t.vertex_count();
  a.local_count = t.local_count();
  a.pixel_count = static_cast<int>(t.cols());
  a.srbf_count = static_cast<int>(m.light);
  a.bandwidth = bandwidth;
  a.ridge = p.ridge;
  a.rank_view = m.rank_view;
  a.rank_light = m.rank_light;
  a.rank_vertex = m.rank_vertex;
  a.precision = p.precision;
  a.light = p.light;
  a.light_srbfs = p.light_srbfs;
  a.light_rounds = p.light_rounds;
  a.signal = p.signal;
  a.brdf_terms = p.signal == Signal::kBrdf ? p.brdf_terms : 0;
  const auto r1 = static_cast<std::size_t>(m.rank_view),
             r2 = static_cast<std::size_t>(m.rank_light),
             r3 = static_cast<std::size_t>(m.rank_vertex), nt = m.light,
             mm = static_cast<std::size_t>(a.local_count);
  const auto q = [&](double v, const char* what) {
    return encode_value(static_cast<float>(v), p.precision, what);
  };
  a.view_basis.resize(mm * r1);
  for (std::size_t i = 0; i < mm; ++i)
    for (std::size_t j = 0; j < r1; ++j)
      a.view_basis[i * r1 + j] =
          q(view(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)), "basis");
  const std::size_t clusters = m.clusters.size();
  a.light_bases.assign(clusters * nt * r2, 0.0f);
  a.duals.assign(clusters * r3 * r1 * r2, 0.0f);
  for (std::size_t c = 0; c < clusters; ++c) {
    const CtaCluster& cl = m.clusters[c];
    for (std::size_t l = 0; l < nt; ++l)
      for (std::size_t i = 0; i < r2; ++i)
        a.light_bases[(c * nt + l) * r2 + i] =
            q(cl.light(static_cast<Eigen::Index>(l), static_cast<Eigen::Index>(i)), "basis");
    for (Eigen::Index j = 0; j < cl.dual.rows(); ++j)
      for (std::size_t k = 0; k < r1 * r2; ++k)
        a.duals[(c * r3 + static_cast<std::size_t>(j)) * r1 * r2 + k] =
            q(cl.dual(j, static_cast<Eigen::Index>(k)), "basis");
  }
  a.ids = m.assignments;
  a.weights.resize(a.vertices * r3);
  for (std::size_t x = 0; x < a.vertices; ++x)
    for (std::size_t j = 0; j < r3; ++j)
      a.weights[x * r3 + j] =
          q(m.weights(static_cast<Eigen::Index>(x), static_cast<Eigen::Index>(j)), "weight");
  return a;
}

/// ||T~ - T||_F / ||T||_F of the stored (decoded) model in the pixel basis, T~'s row (x, m)
/// being g (U K_x U_c^T)[m]^T for the light step's operator g (N x n_t):
/// ||T~_x||^2 = tr(K_x G_c K_x^T H) with G_c = U_c^T P U_c, P = g^T g, H = U^T U,
/// K_x = refold(V_c^T W_x), and <T~, T> summed over T's stored entries.
double stored_error(const SrbfCtaArrays& a, const TransferMatrix& t, const Eigen::MatrixXd& g) {
  const CrossTerm<double> cross(g);
  const Eigen::MatrixXd pm = g.transpose() * g;
  const auto r1 = a.rank_view, r2 = a.rank_light, r3 = a.rank_vertex, nt = a.srbf_count,
             mm = a.local_count;
  const Eigen::Map<const MatF> uf(a.view_basis.data(), mm, r1);
  const Eigen::MatrixXd u = uf.cast<double>();
  const Eigen::MatrixXd h = u.transpose() * u;
  const std::size_t clusters = a.clusters();
  std::vector<Eigen::MatrixXd> uc(clusters), gc(clusters);
  tbb::parallel_for(std::size_t{0}, clusters, [&](std::size_t c) {
    uc[c] =
        Eigen::Map<const MatF>(a.light_bases.data() + c * static_cast<std::size_t>(nt) * r2, nt, r2)
            .cast<double>();
    gc[c] = uc[c].transpose() * pm * uc[c];
  });
  const double approx = deterministic_sum(a.vertices, 8, [&](std::size_t begin, std::size_t end) {
    double acc = 0;
    Eigen::VectorXd q;
    for (std::size_t x = begin; x != end; ++x) {
      const std::size_t c = a.ids[x];
      const Eigen::Map<const MatF> v(a.duals.data() + c * static_cast<std::size_t>(r3) * r1 * r2,
                                     r3, r1 * r2);
      const Eigen::Map<const Eigen::RowVectorXf> w(a.weights.data() + x * r3, r3);
      const Eigen::RowVectorXd kv = w.cast<double>() * v.cast<double>();
      const Eigen::Map<const RowMajorMatrixXd> k(kv.data(), r1, r2);
      acc += ((k * gc[c]).array() * (h * k).array()).sum();
      const MatF rows = (u * k * uc[c].transpose()).cast<float>();  // M x n_t
      for (int m = 0; m < mm; ++m)
        acc -= 2.0 * cross(t, x * static_cast<std::size_t>(mm) + static_cast<std::size_t>(m),
                           rows.row(m).data(), q);
    }
    return acc;
  });
  double t_sq = 0;
  for (std::size_t e = 0; e < t.nnz(); ++e) t_sq += static_cast<double>(t.value(e)) * t.value(e);
  return t_sq > 0 ? std::sqrt(std::max(0.0, approx + t_sq) / t_sq) : 0.0;
}

/// ||Y - Psi T||_F / ||Psi T||_F in the pixel basis, Y_x (K x n_t SRBF coefficients, from
/// `approx`) the approximation of vertex x's folded rows: per vertex ||G Y_x^T||^2 =
/// sum((Y_x P) .* Y_x), and <G Y_x^T, Psi T_x> = <(Psi^T Y_x) G^T, T_x> over T's stored entries.
double folded_error(const TransferMatrix& t, const SrbfProjector& p, const CubemapLayout& layout,
                    const BrdfFold& fold,
                    const std::function<void(std::size_t, RowMajorMatrixXd&)>& approx) {
  const Eigen::MatrixXd g = pixel_values(p, layout);
  const CrossTerm<float> cross(g);
  const Eigen::MatrixXd pm = g.transpose() * g;
  const auto mm = static_cast<std::size_t>(t.local_count());
  const Eigen::MatrixXd psi_t = fold.light.transpose();
  const double approx_sq =
      deterministic_sum(t.vertex_count(), 8, [&](std::size_t begin, std::size_t end) {
        double acc = 0;
        RowMajorMatrixXd y;
        Eigen::VectorXf q;
        for (std::size_t x = begin; x != end; ++x) {
          approx(x, y);
          acc += ((y * pm).array() * y.array()).sum();
          const MatF rows = (psi_t * y).cast<float>();  // M x n_t
          for (std::size_t j = 0; j < mm; ++j)
            acc -= 2.0 * cross(t, x * mm + j, rows.row(static_cast<Eigen::Index>(j)).data(), q);
        }
        return acc;
      });
  const double t_sq = folded_squared_norm(t, fold);
  return t_sq > 0 ? std::sqrt(std::max(0.0, approx_sq + t_sq) / t_sq) : 0.0;
}

/// The stored model's error against the folded transfer, from the decoded light bases, duals and
/// weights and the term-space view basis `u` (K x R1, rounded like the stored values).
double folded_stored_error(const SrbfCtaArrays& a, const Eigen::MatrixXd& u,
                           const TransferMatrix& t, const SrbfProjector& p,
                           const CubemapLayout& layout, const BrdfFold& fold) {
  const auto r1 = a.rank_view, r2 = a.rank_light, r3 = a.rank_vertex, nt = a.srbf_count;
  std::vector<Eigen::MatrixXd> uc(a.clusters());
  for (std::size_t c = 0; c < uc.size(); ++c)
    uc[c] =
        Eigen::Map<const MatF>(a.light_bases.data() + c * static_cast<std::size_t>(nt) * r2, nt, r2)
            .cast<double>();
  return folded_error(t, p, layout, fold, [&](std::size_t x, RowMajorMatrixXd& y) {
    const std::size_t c = a.ids[x];
    const Eigen::Map<const MatF> v(a.duals.data() + c * static_cast<std::size_t>(r3) * r1 * r2, r3,
                                   r1 * r2);
    const Eigen::Map<const Eigen::RowVectorXf> w(a.weights.data() + x * r3, r3);
    const Eigen::RowVectorXd kv = w.cast<double>() * v.cast<double>();
    const Eigen::Map<const RowMajorMatrixXd> k(kv.data(), r1, r2);
    y = u * k * uc[c].transpose();
  });
}

class SrbfCtaCompressor final : public Compressor {
 public:
  explicit SrbfCtaCompressor(Params p) : p_(std::move(p)) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    const TransferMatrix& t = input.transfer;
    if (t.rows() == 0) throw ParameterError(fmt::format("{}: the transfer has no rows", kName));
    const auto total = static_cast<std::int64_t>(t.rows());
    const std::int64_t projection_budget = total / 4;
    const auto centres = icosphere_vertices(icosphere_level_for_count(p_.srbfs));
    const double bandwidth = uniform_gaussian_bandwidth(centres) / (p_.spread * p_.spread);
    const auto projector = std::make_shared<const SrbfProjector>(
        transfer_basis(p_.srbfs, bandwidth), input.cubemap, p_.ridge);
    // Wide or dense SRBFs make the Gram matrix singular to rounding; the ridge keeps the solve
    // stable but then bounds the fit's accuracy, which the user should know. Double precision
    // loses all digits of an unregularised solve past 1e16.
    if (projector->gram_condition_number() > kIllConditionedGram)
      log_warn_named("srbf-gram-ill-conditioned",
                     "{}: the Gram matrix of {} SRBFs (spread {}) has condition number {:.3g}; "
                     "{}",
                     kName, p_.srbfs, p_.spread, projector->gram_condition_number(),
                     projector->alpha() > 0
                         ? fmt::format("solved with the ridge alpha = {:.3g} (condition {:.3g}), "
                                       "which limits how closely the SRBFs can fit T",
                                       projector->alpha(), projector->condition_number())
                         : std::string("solved without a ridge (ridge = 0): the projection "
                                       "amplifies rounding errors"));
    // The BRDF signal: the paper's K view terms, Psi X_x, replace the M cells in the view mode.
    std::optional<BrdfFold> fold;
    if (p_.signal == Signal::kBrdf) fold = fold_brdf(input.grid, p_.brdf, p_.brdf_terms);
    Projection proj;
    std::vector<float> folded;
    if (fold) {
      const auto t1 = Clock::now();
      folded = project_folded(t, *projector, fold->light, progress, projection_budget);
      proj.seconds = std::chrono::duration<double>(Clock::now() - t1).count();
    } else {
      proj = project_rows(t, *projector, input.cubemap, progress, projection_budget);
    }
    log_debug(
        "{}: {} {} onto {} SRBFs (lambda {:.4g}, Gram condition {:.3g}, ridge alpha {:.3g}) in "
        "{:.2f} s",
        kName, fold ? t.vertex_count() * static_cast<std::size_t>(p_.brdf_terms) : t.rows(),
        fold ? "folded rows" : "rows", p_.srbfs, bandwidth, projector->gram_condition_number(),
        projector->alpha(), proj.seconds);
    double srbf_error = proj.frobenius_error;
    if (fold) {
      const auto t1 = Clock::now();
      const std::size_t per_vertex = static_cast<std::size_t>(p_.brdf_terms) * p_.srbfs;
      srbf_error = folded_error(
          t, *projector, input.cubemap, *fold, [&](std::size_t x, RowMajorMatrixXd& y) {
            y = Eigen::Map<const MatF>(folded.data() + x * per_vertex, p_.brdf_terms, p_.srbfs)
                    .cast<double>();
          });
      log_info(
          "{}: BRDF-weighted signal: Cook-Torrance kd {}, m {}, F0 {} in {} terms (the truncation "
          "drops {:.3g} of the weighted kernel's squared singular values); SRBF alone: relative "
          "Frobenius error {:.4f} (SE ratio {:.3f} %) against the {}-term signal (measured in "
          "{:.1f} s)",
          kName, p_.brdf.diffuse, p_.brdf.roughness, p_.brdf.fresnel0, p_.brdf_terms,
          fold->dropped_fraction(), srbf_error, 100.0 * srbf_error * srbf_error, p_.brdf_terms,
          std::chrono::duration<double>(Clock::now() - t1).count());
    }
    CtaOptions o = p_.cta;
    const std::int64_t passes = 2 + o.clustering_iterations + o.approximation_iterations;
    std::int64_t done = 0, reported = 0;
    o.on_pass = [&](const CtaPass& pass) {
      log_debug("{}: {} pass {}: squared error {:.6g}, {} vertices moved", kName, pass.phase,
                pass.iteration, pass.squared_error, pass.moved);
      done = std::min(passes - 1, done + 1);
      const std::int64_t target = (total - projection_budget) * done / passes;
      progress.advance(target - reported);
      reported = target;
    };
    const TensorView view =
        fold ? TensorView{folded, t.vertex_count(), static_cast<std::size_t>(p_.brdf_terms),
                          static_cast<std::size_t>(p_.srbfs)}
             : TensorView{proj.coefficients, t.vertex_count(),
                          static_cast<std::size_t>(t.local_count()),
                          static_cast<std::size_t>(p_.srbfs)};
    // A long CTA saves its state at most every kCheckpointSeconds (after the initialisation and
    // after clustering iterations) so that a killed run resumes; a finished run removes it.
    const std::filesystem::path checkpoint = cta_checkpoint_path(cta_checkpoint_key(view, o));
    // Not on several ranks: each would decide alone whether to resume (a rank that saw another
    // file would run other collectives than the rest) and write the file on its own clock.
    const Communicator* ranks = collective();
    const bool checkpoints = ranks == nullptr || !ranks->distributed();
    std::optional<CtaCheckpoint> resume;
    if (checkpoints) resume = read_cta_checkpoint(checkpoint);
    if (resume) {
      o.resume = &*resume;
      log_info(
          "{}: resuming the clustered tensor approximation from {} (after {} clustering "
          "iterations)",
          kName, checkpoint.string(), resume->model.clustering_iterations);
    }
    auto last_checkpoint = Clock::now();
    o.on_checkpoint = [&](const CtaCheckpoint& c) {
      if (!checkpoints || std::chrono::duration<double>(Clock::now() - last_checkpoint).count() <
                              kCheckpointSeconds)
        return;
      const auto t1 = Clock::now();
      try {
        std::filesystem::create_directories(checkpoint.parent_path());
        save_cta_checkpoint(c).write(checkpoint);
        log_debug("{}: checkpoint after {} clustering iterations in {:.2f} s ({})", kName,
                  c.model.clustering_iterations,
                  std::chrono::duration<double>(Clock::now() - t1).count(), checkpoint.string());
      } catch (const std::exception& e) {
        log_warn_named("srbf_cta-checkpoint-not-written",
                       "{}: the CTA's checkpoint could not be written ({}); a killed run will "
                       "start again",
                       kName, e.what());
      }
      last_checkpoint = Clock::now();
    };
    const CtaModel model = clustered_tensor_approximation(view, o);
    std::error_code removed;
    if (checkpoints) std::filesystem::remove(checkpoint, removed);
    resume.reset();
    SrbfCtaArrays a =
        encode(model, fold ? Eigen::MatrixXd(fold->view * model.view_basis) : model.view_basis, p_,
               t, bandwidth);
    a.srbf_frobenius_error = srbf_error;
    const auto t0 = Clock::now();
    if (fold) {
      const auto q = [&](double v) {
        return static_cast<double>(encode_value(static_cast<float>(v), p_.precision, "basis"));
      };
      a.frobenius_error = folded_stored_error(a, model.view_basis.unaryExpr(q), t, *projector,
                                              input.cubemap, *fold);
    }
    auto out = std::make_unique<SrbfCtaTransfer>(std::move(a), projector);
    // Against T, the stored model is read through its own light step (light_operator()); the
    // BRDF signal's reference is the folded transfer instead, set above.
    if (!fold) out->declare_model_error(t);
    const SrbfCtaArrays& stored = out->arrays();
    log_info(
        "{}: {} clusters, ranks ({}, {}, {}); projection {:.1f} s, CTA initialisation {:.1f} s, "
        "clustering {:.1f} s ({} iterations), approximation {:.1f} s ({} iterations), error "
        "{:.1f} s; relative Frobenius error: SRBF {:.4f}, SRBF + CTA {:.4f} (SE ratios {:.3f} % "
        "and {:.3f} %, {})",
        kName, model.clusters.size(), stored.rank_view, stored.rank_light, stored.rank_vertex,
        proj.seconds, model.times.initialisation, model.times.clustering,
        model.clustering_iterations, model.times.approximation, model.approximation_iterations,
        std::chrono::duration<double>(Clock::now() - t0).count(), stored.srbf_frobenius_error,
        stored.frobenius_error, 100.0 * stored.srbf_frobenius_error * stored.srbf_frobenius_error,
        100.0 * stored.frobenius_error * stored.frobenius_error,
        fold ? fmt::format("against the {}-term BRDF-weighted signal", p_.brdf_terms)
             : std::string("against T"));
    progress.finish();
    return out;
  }

 private:
  Params p_;
};

}  // namespace

void SrbfCtaTransfer::declare_model_error(const TransferMatrix& t) {
  a_.frobenius_error = stored_error(a_, t, light_operator());
}

SrbfBasis transfer_basis(int srbf_count, double bandwidth) {
  SrbfBasis b;
  b.kernel = SrbfKernel::kGaussian;
  b.centres = icosphere_vertices(icosphere_level_for_count(srbf_count));
  if (static_cast<int>(b.centres.size()) != srbf_count)
    throw ParameterError(
        fmt::format("{}: {} SRBFs is not an icosphere vertex count (12, 42, 162, 642, 2562, ...)",
                    kName, srbf_count));
  b.bandwidths.assign(b.centres.size(), bandwidth);
  return b;
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "T's rows in uniform Gaussian SRBFs, the vertex x direction x SRBF tensor by clustered "
      "tensor approximation (Tsai and Shih 2006): per cluster a light basis and a dual vertex "
      "basis, one view basis, per vertex R_vert weights";
  e.params = {
      {"srbfs",
       ParamType::kInt,
       "642",
       12.0,
       10242.0,
       {},
       "transfer SRBFs n_t: icosphere vertex count 12, 42, 162, 642, 2562 or 10242"},
      {"spread",
       ParamType::kReal,
       "1",
       0.05,
       20.0,
       {},
       "SRBF width relative to the spacing rule (sigma = pi/40 at 642); the bandwidth goes as "
       "1 / spread^2"},
      {"ridge",
       ParamType::kReal,
       "1e-6",
       0.0,
       1.0,
       {},
       "regularisation of the projections, relative to the largest Gram diagonal entry"},
      {"clusters", ParamType::kInt, "16", 1.0, 65536.0, {}, "clusters n_c"},
      {"rank_view",
       ParamType::kInt,
       "0",
       0.0,
       4096.0,
       {},
       "R_view, rank of the shared view (local direction) basis; 0: M, no truncation"},
      {"rank_light", ParamType::kInt, "48", 1.0, 10242.0, {}, "R_light, per-cluster SRBF rank"},
      {"rank_vertex",
       ParamType::kInt,
       "24",
       1.0,
       4096.0,
       {},
       "R_vert, per-cluster vertex rank: the weights a vertex stores"},
      {"clustering_iterations",
       ParamType::kInt,
       "20",
       0.0,
       1000.0,
       {},
       "reclassification passes at most (the clustering phase stops when no vertex moves)"},
      {"clustering_tolerance",
       ParamType::kReal,
       "1e-3",
       0.0,
       1.0,
       {},
       "the clustering phase stops when an iteration lowers the error by at most this fraction "
       "of it; 0: only when no vertex moves"},
      {"approximation_iterations",
       ParamType::kInt,
       "5",
       0.0,
       1000.0,
       {},
       "approximation-phase passes at most (none when rank_view keeps every direction)"},
      {"hooi_sweeps",
       ParamType::kInt,
       "1",
       0.0,
       100.0,
       {},
       "HOOI sweeps (light basis, vertex basis) per cluster refit"},
      {"elbg_rounds", ParamType::kInt, "10", 0.0, 1000.0, {}, "ELBG rounds of the initialisation"},
      {"elbg_dims",
       ParamType::kInt,
       "256",
       0.0,
       1e6,
       {},
       "ELBG works in the top elbg_dims principal directions of the unfolded vertex signals; 0: "
       "in full"},
      {"precision",
       ParamType::kEnum,
       "float16",
       std::nullopt,
       std::nullopt,
       {"float16", "float32"},
       "stored bases and weights: IEEE half (the paper's 16 bits) or f32"},
      {"light",
       ParamType::kEnum,
       "uniform",
       std::nullopt,
       std::nullopt,
       {"uniform", "scattered", "pixel"},
       "how the light reaches the transfer SRBFs: uniform light SRBFs (RLS fit, eq. 13), the "
       "scattered fit of section 5.3, or the pixel quadrature of the inner products"},
      {"light_srbfs",
       ParamType::kInt,
       "0",
       0.0,
       10242.0,
       {},
       "light SRBFs n_l; 0: the transfer SRBFs (uniform) or 162 (scattered)"},
      {"light_rounds",
       ParamType::kInt,
       "40",
       1.0,
       1000.0,
       {},
       "alternating L-BFGS-B rounds of the scattered fit"},
  };
  // The light rank, not the vertex rank: the light mode has to hold a cluster's disjoint cell
  // patches, and it is what limits the error (results/srbf-cta/README.md, "Ranks").
  e.size_knob = SizeKnob{"rank_light", SizeKnob::Direction::kLargerIsMoreStorage, 4.0, 320.0,
                         SizeKnob::Scale::kLinear};
  // The view mode's signal and its parameters (core compress/brdf_signal.h). The folded rows
  // themselves are not read: the SRBF projection folds each vertex's right-hand sides as it
  // goes, which a 48k-vertex scene needs (its folded rows would take 14 GB).
  e.inputs.brdf_signal = true;
  e.lossless = false;
  e.collective = true;         // its cluster refits go through a work queue over the ranks
  e.cost_hint_seconds = 1600;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& ps) -> std::unique_ptr<Compressor> {
    Params p;
    p.srbfs = static_cast<int>(ps.get_int("srbfs"));
    transfer_basis(p.srbfs, 1.0);  // refuses a count that is no icosphere's
    p.spread = ps.get_real("spread");
    p.ridge = ps.get_real("ridge");
    p.cta.clusters = static_cast<int>(ps.get_int("clusters"));
    p.cta.rank_view = static_cast<int>(ps.get_int("rank_view"));
    p.cta.rank_light = static_cast<int>(ps.get_int("rank_light"));
    p.cta.rank_vertex = static_cast<int>(ps.get_int("rank_vertex"));
    p.cta.clustering_iterations = static_cast<int>(ps.get_int("clustering_iterations"));
    p.cta.clustering_tolerance = ps.get_real("clustering_tolerance");
    p.cta.approximation_iterations = static_cast<int>(ps.get_int("approximation_iterations"));
    p.cta.hooi_sweeps = static_cast<int>(ps.get_int("hooi_sweeps"));
    p.cta.elbg_rounds = static_cast<int>(ps.get_int("elbg_rounds"));
    p.cta.elbg_dims = static_cast<int>(ps.get_int("elbg_dims"));
    p.cta.seed = static_cast<std::uint64_t>(ps.get_int("seed"));
    p.precision = ps.get_enum<Precision>(
        "precision", {{"float16", Precision::kFloat16}, {"float32", Precision::kFloat32}});
    p.light = ps.get_enum<LightMode>("light", {{"uniform", LightMode::kUniform},
                                               {"scattered", LightMode::kScattered},
                                               {"pixel", LightMode::kPixel}});
    p.light_srbfs = static_cast<int>(ps.get_int("light_srbfs"));
    p.light_rounds = static_cast<int>(ps.get_int("light_rounds"));
    const BrdfSignalParams signal = brdf_signal_params(ps);
    p.signal = signal.enabled ? Signal::kBrdf : Signal::kCells;
    p.brdf_terms = signal.terms;
    p.brdf = signal.brdf;
    return std::make_unique<SrbfCtaCompressor>(std::move(p));
  };
  e.load = &SrbfCtaTransfer::load;
  e.version = 6;
  e.published = {
      {"bunny",
       {{"srbfs", "642"},
        {"clusters", "170"},
        {"rank_view", "8"},
        {"rank_light", "48"},
        {"rank_vertex", "24"}},
       "61k vertices, 16 BRDF terms: SE ratio 1.28 % (SRBF), 3.64 % (SRBF + CTA); 15.89 MB "
       "from 22.35 GB raw; CTA compression 29 hr 2 min",
       "Tsai and Shih 2006, Table 1"},
  };
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::srbf_cta
