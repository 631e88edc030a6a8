#pragma once
// A material stored as three factors per texel, f(t, d, e) ~ s_t P_t(d) Q_t(h(d, e)) R_t(e) per
// colour channel, normalised, clustered and quantised as Suykens et al. 2003 store a factored
// BTF (sections 5 and 6): any factorisation that produces P, Q and R (the material backends
// `cmf` and `hf`) encodes through here and shades through kernels/factored_material.cl.
// A texel may hold K terms sharing its Q (the paper's multiple-term approximation, eq. 3, of the
// step after the halfway factor): f ~ Q(h) sum_k s_tk P_tk(d) R_tk(e), every term normalised
// and given its scale as a single term is; the P of all terms share one codebook, as do the R.
//
//   P  on the light grid (S x S cells: the light is always a bin centre), M values per channel
//   Q  on a half_side x half_side HemisphereGrid of halfway directions, read with the
//      sphere-bilinear interpolation of btf_view_samples at halfway_f(d, e)
//   R  on the view grid, read with btf_view_samples at e
//
// Q's halfway interpolation is a property of the factored model, chosen by the backend that fits
// it (State::interpolation): linear, sum_a w_a Q_a (a texture's bilinear filter; `cmf` fits that
// model), or geometric, prod_a Q_a^w_a = exp(sum_a w_a log Q_a) (the interpolation a fit in
// logarithms solves for: `hf`). Both are homogeneous of degree 1 in Q (the weights sum to 1), so
// the normalisation below factors either exactly. In the geometric mode a Q below FLT_MIN (an
// 8-bit code 0, an underflow) is read as FLT_MIN: its logarithm stays finite, so a neighbour of
// weight 0 contributes nothing, and one of weight w > 0 drives the product towards 0, the limit of
// the geometric mean as that Q goes to 0.
//
// Encoding (encode_factored_material):
//   1. normalisation: each factor of each texel, term and channel divided by its maximum, so it
//      lies in [0, 1]; the three maxima multiply into the term's RGB scale (the scale map);
//   2. clustering: per factor set (all P, all Q, all R) k-means (k-means++ seeds) on the
//      normalised RGB vectors gives a codebook and an index map; clusters = 0 keeps one factor
//      per texel (the paper's "factored" size);
//   3. quantisation (optional): every codebook entry in 8 bits with one scale per entry
//      (numeric/quantization.h, non-negative range; codes here and in the scale map linear in
//      x^(1 / code_gamma): 1 is the paper's linear textures, 2.2 by default), the scale map in 8
//      bits per channel with one global RGB scale (the paper's five 8-bit textures);
//   4. (refit_scale, not in the paper) each texel's scales refitted by least squares to its
//      ABRDF with the codebook entries it was given, before the scale map is quantised:
//      clustering moves a texel's factors to a centroid whose maximum is no longer 1 (K terms:
//      the non-negative least-squares scales, by coordinate descent on the K x K normal
//      equations; one term: its closed form).
// What the material evaluates is the decoded state, so save and load reproduce it bit for bit.
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"

namespace prt {

class ArchiveReader;

/// The most terms a factored texel may hold (the shading kernel's private arrays).
inline constexpr int kMaxFactorTerms = 4;

/// Per-texel factors before normalisation, packed RGB, K = terms:
/// p[((texel * K + k) * M + j) * 3 + c], q[(texel * H + a) * 3 + c],
/// r[((texel * K + k) * V + v) * 3 + c]; all >= 0 and finite.
struct AbrdfFactors {
  int texels = 0, light_count = 0, half_count = 0, view_count = 0, terms = 1;
  std::vector<float> p, q, r;
  AbrdfFactors() = default;
  AbrdfFactors(int texel_count, int m, int h, int v, int term_count = 1);
};

/// How Q is read between its halfway-grid samples (the file comment).
enum class HalfwayInterpolation { kLinear, kGeometric };

/// "linear" / "geometric", as the archive stores it.
const char* halfway_interpolation_name(HalfwayInterpolation mode);

struct FactorCoding {
  int half_side = 16;  ///< Q's grid: half_side x half_side halfway directions
  int clusters = 256;  ///< per factor set, at most the texel count; 0: no clustering
  bool quantize = true;
  bool refit_scale = true;  ///< least-squares texel scales after clustering (not in the paper)
  double code_gamma = 2.2;  ///< 8-bit codes linear in x^(1/gamma); 1: the paper's linear codes
  std::uint64_t seed = 0;
  int kmeans_iterations = 50;
  /// Set by the backend to the interpolation its fit assumes, not a user parameter.
  HalfwayInterpolation interpolation = HalfwayInterpolation::kLinear;
  /// Set by the backend: the P R terms its factoriser gives per texel (1 .. kMaxFactorTerms).
  int terms = 1;
};

/// The parameters every factored material backend takes (half_side, clusters, quantize,
/// refit_scale, code_gamma; the shared seed seeds k-means++), read from `p`;
/// factor_coding_params() declares them.
FactorCoding factor_coding(const ParamSet& p);
std::vector<ParamSpec> factor_coding_params();

/// Seconds of a factored compression (reported by `btf-table`): factorization_seconds is the
/// caller's, recorded in the material's timings; the others encode_factored_material measures.
struct FactorCodingTimes {
  double factorization_seconds = 0;
  double clustering_seconds = 0;
  double quantization_seconds = 0;
};

class FactoredMaterial final : public CompressedMaterial {
 public:
  /// The decoded state. Codebooks are (entries) x (values) x 3 floats. Q's index has one entry
  /// per texel; P's and R's indices and the scale one per texel and term, at texel * terms + k
  /// (the scale RGB, at (texel * terms + k) * 3).
  struct State {
    std::string backend;
    MaterialSampling sampling;
    int half_side = 0;
    int terms = 1;
    int clusters_p = 0, clusters_q = 0, clusters_r = 0;
    bool quantized = false;
    double code_gamma = 1.0;  ///< of the codebook codes (quantized only)
    HalfwayInterpolation interpolation = HalfwayInterpolation::kLinear;
    std::vector<float> codebook_p, codebook_q, codebook_r;
    std::vector<std::uint32_t> index_p, index_q, index_r;
    std::vector<float> scale;  ///< texels x terms x 3
    /// The encoded bytes when quantized (what save writes; decoded into the floats above).
    std::vector<std::uint8_t> codes_p, codes_q, codes_r, scale_codes;
    std::vector<float> entry_scale_p, entry_scale_q, entry_scale_r;  ///< per codebook entry
    std::vector<float> scale_global;                                 ///< 3: per channel
    double error = 0;
    nlohmann::json parameters = nlohmann::json::object();  ///< the fit's, for provenance
    /// Seconds of the factorisation, clustering and quantisation (not saved: a loaded
    /// material has none).
    nlohmann::json timings = nlohmann::json::object();
  };

  explicit FactoredMaterial(State state);

  std::string backend() const override { return state_.backend; }
  StorageReport storage() const override;
  double flops_per_pixel() const override;
  double declared_error_bound() const override { return state_.error; }
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::pixel_bins(state_.sampling.light_side);
  }
  MaterialSampling sampling() const override { return state_.sampling; }
  Rgb reflectance(int texel, int view, int light) const override;
  void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out, TexelFilter filter) const override;
  std::unique_ptr<DeviceMaterial> upload(ClContext& context,
                                         std::span<const CompressedMaterial* const> parts,
                                         const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

  const State& state() const { return state_; }
  int half_count() const { return state_.half_side * state_.half_side; }
  /// Bytes of the unclustered float factors (the paper's "factored data size").
  std::uint64_t factored_bytes() const;
  /// The terms s_k P_k Q R_k of one sample, k < terms (out holds at least terms values); their
  /// sum is reflectance().
  void term_values(int texel, int view, int light, std::span<Rgb> out) const;

  /// Reads what save() wrote; InputError naming the file on anything inconsistent.
  static std::unique_ptr<FactoredMaterial> load(const ArchiveReader& archive,
                                                const std::string& backend);

 private:
  const float* p_entry(int texel, int term) const;
  const float* q_entry(int texel) const;
  const float* r_entry(int texel, int term) const;
  const float* scale_of(int texel, int term) const;
  State state_;
  std::vector<Vec3> lights_;  ///< light directions in float
  std::vector<Vec3> views_;   ///< view directions in float, clamped as shading clamps them
};

/// Factors one ABRDF channel: f holds the M V samples of one texel and channel (s = view * M +
/// light), p (terms x M, term k at k M), q (half_count) and r (terms x V) receive its factors.
/// Called concurrently.
using ChannelFactorizer = std::function<void(std::span<const double> f, std::span<double> p,
                                             std::span<double> q, std::span<double> r)>;

/// The ChannelFactorizer of a shared factoriser object with a const factor(f, p, q, r).
template <typename Factorizer>
ChannelFactorizer channel_factorizer(std::shared_ptr<const Factorizer> f) {
  return [f](std::span<const double> v, std::span<double> p, std::span<double> q,
             std::span<double> r) { f->factor(v, p, q, r); };
}

/// Every texel and channel of `btf` through `factor` (giving `terms` P R terms), in parallel over
/// texels; `progress` advances by one per texel. Throws ParameterError naming `backend` when a
/// factor is negative or not finite.
AbrdfFactors factor_texels(const Btf& btf, int half_count, const ChannelFactorizer& factor,
                           const std::string& backend, Progress& progress, int terms = 1);

/// A material backend's compress(): factor_texels with a progress bar, then
/// encode_factored_material; the material's timings hold factorization_seconds (the whole
/// factorisation, its set-up included), clustering and quantisation seconds.
std::unique_ptr<FactoredMaterial> compress_factored(const std::string& backend, const Btf& btf,
                                                    int half_side, const ChannelFactorizer& factor,
                                                    const FactorCoding& coding,
                                                    nlohmann::json parameters,
                                                    double setup_seconds = 0);

/// The MaterialCompressor of a factored material backend: compress() calls `setup` once per BTF
/// (what depends only on the sampling; timed with the factorisation) for the channel
/// factoriser, then compress_factored with coding.half_side.
class FactoredCompressor final : public MaterialCompressor {
 public:
  using Setup = std::function<ChannelFactorizer(const Btf& btf)>;
  FactoredCompressor(std::string backend, Setup setup, FactorCoding coding,
                     nlohmann::json parameters);
  std::unique_ptr<CompressedMaterial> compress(const MaterialInput& input,
                                               Progress& progress) const override;

 private:
  std::string backend_;
  Setup setup_;
  FactorCoding coding_;
  nlohmann::json parameters_;
};

/// A MaterialEntry::load for `backend`: FactoredMaterial::load.
std::function<std::unique_ptr<CompressedMaterial>(const ArchiveReader&)> factored_loader(
    std::string backend);

/// Steps 1-4 of the file comment, with coding.interpolation as the material's (the scale refit
/// evaluates the model through it), then the error against `full` (stored as the declared
/// bound). `parameters` records the fit's parameters.
std::unique_ptr<FactoredMaterial> encode_factored_material(
    std::string backend, const Btf& full, int half_side, const AbrdfFactors& factors,
    const FactorCoding& coding, nlohmann::json parameters, FactorCodingTimes* times = nullptr);

}  // namespace prt
