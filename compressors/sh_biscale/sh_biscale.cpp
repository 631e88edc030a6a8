#include "sh_biscale/sh_biscale.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "prtlab/base/error.h"
#include "prtlab/compress/sh_matrix_model.h"
#include "prtlab/sphere/hemisphere_projection.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/sh_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::sh_biscale {
namespace {

struct ShBiscaleParams {
  int order = 5;
  Projection projection = Projection::kZero;
};

class ShBiscaleCompressor final : public Compressor {
 public:
  explicit ShBiscaleCompressor(ShBiscaleParams p) : p_(p) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    if (input.sh == nullptr)
      throw ParameterError(fmt::format(
          "{}: the input holds no SH transfer (the entry asks for order {})", kName, kInputOrder));
    const ShTransfer& sh = *input.sh;
    if (sh.order() < p_.order)
      throw ParameterError(fmt::format(
          "{}: order = {} needs an SH transfer of order {} or more, the input has order {}", kName,
          p_.order, p_.order, sh.order()));
    if (sh.vertex_count() != input.transfer.vertex_count())
      throw ParameterError(fmt::format("{}: the SH transfer has {} vertices, T {}", kName,
                                       sh.vertex_count(), input.transfer.vertex_count()));
    ShBiscaleArrays a;
    a.vertices = sh.vertex_count();
    a.order = p_.order;
    a.projection = p_.projection;
    a.matrices = vertex_matrices(sh, p_.order, p_.projection);
    a.local_count = input.grid.cell_count();
    a.frobenius_error =
        ShMatrixModel(input.cubemap, input.grid, a.order, a.order)
            .relative_frobenius_error(input.transfer, [&](std::size_t v, std::span<double> x) {
              const float* m = a.matrices.data() + v * x.size();
              std::copy(m, m + x.size(), x.begin());
            });
    progress.finish();
    return std::make_unique<ShBiscaleTransfer>(std::move(a));
  }

 private:
  ShBiscaleParams p_;
};

Projection projection_from(std::string_view name) {
  for (Projection p : {Projection::kZero, Projection::kLeastSquares})
    if (to_string(p) == name) return p;
  throw ParameterError(
      fmt::format("{}: projection '{}' is none of zero, least_squares", kName, name));
}

}  // namespace

std::string_view to_string(Projection p) {
  return p == Projection::kZero ? "zero" : "least_squares";
}

std::vector<float> vertex_matrices(const ShTransfer& sh, int order, Projection projection) {
  if (order < 1 || order > sh.order())
    throw ParameterError(fmt::format("{}: order {} is not in 1..{} (the SH transfer's order)",
                                     kName, order, sh.order()));
  const int n = order * order, full = sh.dim();
  const auto nn = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  std::vector<float> out(sh.vertex_count() * nn);
  const std::optional<HemisphereProjector> projector =
      projection == Projection::kLeastSquares
          ? std::optional<HemisphereProjector>(HemisphereProjector(order))
          : std::nullopt;
  tbb::parallel_for(std::size_t{0}, sh.vertex_count(), [&](std::size_t v) {
    const std::span<const double> m = sh.matrix(v);
    float* dst = out.data() + v * nn;
    Eigen::VectorXd b(n);
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < n; ++i) b[i] = m[static_cast<std::size_t>(i) * full + k];
      const Eigen::VectorXd c = projector ? projector->solve(b) : b;
      for (int i = 0; i < n; ++i)
        dst[static_cast<std::size_t>(i) * n + k] = static_cast<float>(c[i]);
    }
  });
  return out;
}

std::string ShBiscaleTransfer::light_basis() const {
  return fmt::format("sh{}", a_.order);
}

StorageReport ShBiscaleTransfer::storage() const {
  StorageReport r;
  r.components.push_back(
      {"matrices", a_.matrices.size() * std::uint64_t{4},
       fmt::format("f32 {} x {} matrix per vertex (local SH i x global SH k, row-major), vertex "
                   "after vertex; {} projection",
                   a_.n(), a_.n(), to_string(a_.projection))});
  return r;
}

double ShBiscaleTransfer::flops_per_relight() const {
  const double n = a_.n();
  return 2.0 * n * n * static_cast<double>(a_.vertices);
}

LightCoeffs ShBiscaleTransfer::project_light(const Cubemap& radiance) const {
  const ShCoeffs sh = sh_project(radiance, a_.order);
  LightCoeffs out{light_basis(), std::vector<Rgb>(sh.coeffs.size())};
  for (std::size_t k = 0; k < sh.coeffs.size(); ++k) out.values[k] = Rgb(sh.coeffs[k]);
  return out;
}

ModelRadiance ShBiscaleTransfer::model_radiance(const Cubemap& radiance) const {
  const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(a_.local_count))));
  const ShMatrixModel model(radiance.layout, HemisphereGrid(side), a_.order, a_.order);
  const auto nn = static_cast<std::size_t>(a_.n()) * static_cast<std::size_t>(a_.n());
  return model.radiance(
      radiance, a_.vertices,
      [&](std::size_t v, std::span<double> x) {
        std::copy_n(a_.matrices.data() + v * nn, nn, x.begin());
      },
      [&](std::size_t v, std::span<double> x) {
        const float* m = a_.matrices.data() + v * nn;
        for (std::size_t i = 0; i < nn; ++i) x[i] = std::abs(m[i]);
      });
}

void ShBiscaleTransfer::check_light(const LightCoeffs& light) const {
  if (light.basis != light_basis() || light.values.size() != static_cast<std::size_t>(a_.n()))
    throw ParameterError(fmt::format(
        "{}: the light is in basis '{}' with {} values, the transfer needs '{}' with {}", kName,
        light.basis, light.values.size(), light_basis(), a_.n()));
}

void ShBiscaleTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_light(light);
  out.ensure_shape(RadianceBasis::kSphericalHarmonics, a_.n(), a_.vertices);
  relight_rows(a_, light.values, {}, true, out.values);
}

void ShBiscaleTransfer::relight_vertices(const LightCoeffs& light,
                                         std::span<const std::uint32_t> vertices,
                                         LocalRadiance& out) const {
  check_light(light);
  check_vertex_subset(vertices, a_.vertices, kName);
  out.ensure_shape(RadianceBasis::kSphericalHarmonics, a_.n(), a_.vertices);
  relight_rows(a_, light.values, vertices, false, out.values);
}

std::unique_ptr<DeviceRelighter> ShBiscaleTransfer::upload(ClContext& context,
                                                           const ParamSet&) const {
  return upload_sh_biscale(context, a_, light_basis());
}

void ShBiscaleTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("sh_biscale_version", kStateVersion);
  archive.add_meta("vertices", a_.vertices);
  archive.add_meta("order", a_.order);
  archive.add_meta("projection", std::string(to_string(a_.projection)));
  archive.add_meta("local_count", a_.local_count);
  archive.add_meta("frobenius_error", a_.frobenius_error);
  archive.add_section("matrices", a_.matrices);
}

std::unique_ptr<CompressedTransfer> ShBiscaleTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("sh_biscale_version");
  if (version != kStateVersion)
    throw fail(fmt::format("state version {} is not the version {} this build reads{}", version,
                           kStateVersion,
                           version == 1 ? " (version 1 holds no local bin count and no model "
                                          "error; compress the transfer again)"
                                        : ""));
  ShBiscaleArrays a;
  a.vertices = r.meta_value<std::size_t>("vertices");
  a.order = r.meta_value<int>("order");
  a.local_count = r.meta_value<int>("local_count");
  a.frobenius_error = r.meta_value<double>("frobenius_error");
  const int side = static_cast<int>(std::lround(std::sqrt(std::max(a.local_count, 0))));
  if (a.local_count < 1 || side * side != a.local_count)
    throw fail(fmt::format("local_count {} is no square grid S^2 >= 1", a.local_count));
  if (!(std::isfinite(a.frobenius_error) && a.frobenius_error >= 0))
    throw fail("the model's Frobenius error is not a finite non-negative number");
  try {
    a.projection = projection_from(r.meta_value<std::string>("projection"));
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (a.order < 1 || a.order > kInputOrder)
    throw fail(fmt::format("order {} is not in 1..{}", a.order, kInputOrder));
  const auto nn = static_cast<std::uint64_t>(a.n()) * static_cast<std::uint64_t>(a.n());
  if (a.vertices > std::numeric_limits<std::uint32_t>::max() / nn)
    throw fail(
        fmt::format("{} vertices x {} values do not fit the relight's u32 index", a.vertices, nn));
  a.matrices = r.section<float>("matrices", a.vertices * nn);
  if (!std::all_of(a.matrices.begin(), a.matrices.end(), [](float v) { return std::isfinite(v); }))
    throw fail("a matrix entry is not finite");
  return std::make_unique<ShBiscaleTransfer>(std::move(a));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "SH bi-scale macro scale (Sloan et al. 2004): per vertex the n x n SH transfer matrix "
      "from the global SH light to local SH incident radiance, shadowing included";
  e.params = {
      {"order",
       ParamType::kInt,
       "5",
       1.0,
       static_cast<double>(kInputOrder),
       {},
       "SH order of light and local radiance (n = order^2; the paper: 5, n = 25); the scene's SH "
       "transfer is computed at order 10 and cut to this order"},
      {"projection",
       ParamType::kEnum,
       "zero",
       std::nullopt,
       std::nullopt,
       {"zero", "least_squares"},
       "the local radiance's SH coefficients: zero = the projection of the radiance, zero below "
       "the horizon (the paper); least_squares = A^-1 of it, the best fit over the upper "
       "hemisphere (Sloan et al. 2003, appendix; hemisphere_projection.h)"},
  };
  e.inputs.sh_order = kInputOrder;
  e.output_basis = RadianceBasis::kSphericalHarmonics;
  e.size_knob = SizeKnob{"order", SizeKnob::Direction::kLargerIsMoreStorage, 1.0,
                         static_cast<double>(kInputOrder), SizeKnob::Scale::kLinear};
  e.lossless = false;
  e.cost_hint_seconds = 0.04;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    ShBiscaleParams c;
    c.order = static_cast<int>(p.get_int("order"));
    c.projection = p.get_enum<Projection>(
        "projection", {{"zero", Projection::kZero}, {"least_squares", Projection::kLeastSquares}});
    return std::make_unique<ShBiscaleCompressor>(c);
  };
  e.load = &ShBiscaleTransfer::load;
  e.version = 2;
  e.published = {
      {"bunny",
       {{"order", "5"}},
       "25 x 25 SH transfer per vertex (f32: 2.5 KB a vertex); blurrier shadows and lost "
       "specularity against the all-frequency pixel basis",
       "Sun et al. 2008, Fig. 1 and Fig. 5; Sloan et al. 2004, section 4"},
  };
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::sh_biscale
