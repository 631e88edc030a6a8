// `prtlab sh hemisphere`: the least-squares hemispherical SH projection's Gram matrix and the
// error analysis of the zero-hemisphere, odd and even reflection projections (Sloan et al. 2003,
// appendix 9; docs/hemisphere-projection.md). Documented in docs/cli.md (every option and JSON
// key).
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "commands.h"
#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_projection.h"
#include "prtlab/sphere/spherical_harmonics.h"

namespace prt::cli {
namespace {

struct HemisphereOptions {
  int order = 0;
  std::optional<int> odd_order;   ///< unset: the paper's 8, raised to --order
  std::optional<int> even_order;  ///< unset: the paper's 7, raised to --order
  bool json = false;
};

struct Lm {
  int l, m;
};
Lm lm_of(int index) {
  const int l = static_cast<int>(std::sqrt(static_cast<double>(index)));
  return {l, index - l * (l + 1)};
}

// The JSON key of each analysed projection, in HemisphereAnalysis::projections' order.
constexpr const char* kProjectionKeys[] = {"zero_hemisphere", "odd_reflection", "even_reflection",
                                           "even_reflection_same_order"};

std::optional<int> order_option(const std::optional<int>& value, const char* name) {
  if (value && (*value < 1 || *value > kMaxShOrder)) {
    throw ParameterError(fmt::format("{} must be in [1, {}], got {}", name, kMaxShOrder, *value));
  }
  return value;
}

void run_hemisphere(const HemisphereOptions& o) {
  if (o.order < 1 || o.order > kMaxShOrder) {
    throw ParameterError(fmt::format(
        "--order must be in [1, {}] (SH orders: bands l < order), got {}", kMaxShOrder, o.order));
  }
  HemisphereAnalysisOptions options;
  options.odd_order = order_option(o.odd_order, "--odd-order");
  options.even_order = order_option(o.even_order, "--even-order");
  if ((options.odd_order && *options.odd_order < o.order) ||
      (options.even_order && *options.even_order < o.order)) {
    throw ParameterError(fmt::format(
        "--odd-order and --even-order must be at least --order ({}): a projection of lower order "
        "cannot hold the signal",
        o.order));
  }
  const HemisphereAnalysis a = analyse_hemisphere_projection(o.order, options);
  const int n = sh_count(o.order);
  const double largest = a.eigenvalues[0], smallest = a.eigenvalues[n - 1];
  const Lm worst_lm = lm_of(a.most_redundant);

  if (o.json) {
    nlohmann::json discard = nlohmann::json::array();
    for (int i = 0; i < n; ++i) {
      const Lm lm = lm_of(i);
      discard.push_back(
          {{"index", i}, {"l", lm.l}, {"m", lm.m}, {"squared_error", a.discard_error[i]}});
    }
    nlohmann::json projections = nlohmann::json::object();
    for (std::size_t k = 0; k < a.projections.size(); ++k) {
      const HemisphereProjectionError& e = a.projections[k];
      projections[kProjectionKeys[k]] = {{"kind", std::string(to_string(e.kind))},
                                         {"projection_order", e.projection_order},
                                         {"coefficients", e.coefficients},
                                         {"worst", e.worst},
                                         {"average", e.average},
                                         {"worst_rms_percent", e.worst_rms_percent()},
                                         {"average_rms_percent", e.average_rms_percent()}};
    }
    nlohmann::json all = nlohmann::json::array();
    for (int i = 0; i < n; ++i) all.push_back(a.eigenvalues[i]);
    print_json({{"order", o.order},
                {"basis_functions", n},
                {"singular_values",
                 {{"largest", largest},
                  {"smallest", smallest},
                  {"second_smallest",
                   n >= 2 ? nlohmann::json(a.eigenvalues[n - 2]) : nlohmann::json(nullptr)},
                  {"condition_number", largest / smallest},
                  {"all", all}}},
                {"discard_error", discard},
                {"most_redundant",
                 {{"index", a.most_redundant},
                  {"l", worst_lm.l},
                  {"m", worst_lm.m},
                  {"squared_error", a.discard_error[a.most_redundant]}}},
                {"projections", projections}});
    return;
  }

  std::printf("SH order %d (%d basis functions) restricted to the upper hemisphere H (z >= 0)\n\n",
              o.order, n);
  std::printf("Gram matrix A_ik = integral over H of y_i y_k (symmetric positive definite)\n");
  std::printf("  largest singular value          %.6g\n", largest);
  std::printf("  smallest singular value         %.6g\n", smallest);
  if (n >= 2) std::printf("  second-smallest singular value  %.6g\n", a.eigenvalues[n - 2]);
  std::printf("  condition number                %.6g\n\n", largest / smallest);

  std::printf(
      "Squared error over H of approximating each basis function by the others (1 / (A^-1)_ii)\n");
  std::printf("  index   l   m   squared error\n");
  for (int i = 0; i < n; ++i) {
    const Lm lm = lm_of(i);
    std::printf("  %5d  %2d  %2d   %.6g%s\n", i, lm.l, lm.m, a.discard_error[i],
                i == a.most_redundant ? "   <- smallest" : "");
  }
  std::printf(
      "  smallest: l=%d, m=%d (index %d), squared error %.6g: the most redundant basis function "
      "on H\n\n",
      worst_lm.l, worst_lm.m, a.most_redundant, a.discard_error[a.most_redundant]);

  std::printf(
      "Projection error over H for every unit-power signal of order %d (sum c_i y_i, ||c|| = 1)\n",
      o.order);
  std::printf("  squared error: worst = largest eigenvalue of Q, average = trace(Q) / %d\n", n);
  std::printf(
      "  projection        order  coefficients  worst squared  average squared  worst RMS  "
      "average RMS\n");
  for (const HemisphereProjectionError& e : a.projections) {
    std::printf("  %-16s  %5d  %12d  %13.6g  %15.6g  %8.3f %%  %9.3f %%\n",
                std::string(to_string(e.kind)).c_str(), e.projection_order, e.coefficients, e.worst,
                e.average, e.worst_rms_percent(), e.average_rms_percent());
  }
  std::printf("  %-16s  %5d  %12d  %13.6g  %15.6g  %8.3f %%  %9.3f %%   (c = A^-1 b, exact)\n",
              "least_squares", o.order, n, 0.0, 0.0, 0.0, 0.0);
}

}  // namespace

void add_sh_commands(CLI::App& app) {
  CLI::App* sh = app.add_subcommand("sh", "Spherical harmonics: analyses of the SH basis");
  sh->require_subcommand(1);

  auto hemi = std::make_shared<HemisphereOptions>();
  CLI::App* hemi_cmd = sh->add_subcommand(
      "hemisphere",
      "Least-squares hemispherical SH projection (Sloan et al. 2003, appendix 9): A's singular "
      "values, each basis function's discard error, worst/average errors of the zero-hemisphere, "
      "odd and even reflection projections");
  hemi_cmd->add_option("--order", hemi->order, "SH order N of the signals (1..10; n = N^2)")
      ->required();
  // Plain ints parsed by CLI11; whether the user gave them decides the default below.
  auto odd_order = std::make_shared<int>(0), even_order = std::make_shared<int>(0);
  CLI::Option* odd_opt =
      hemi_cmd->add_option("--odd-order", *odd_order,
                           "Order of the odd reflection projection (default: the paper's 8, or "
                           "--order when larger)");
  CLI::Option* even_opt = hemi_cmd->add_option(
      "--even-order", *even_order,
      "Order of the even reflection projection (default: the paper's 7, or "
      "--order when larger); even reflection at --order is always reported too");
  hemi_cmd->add_flag("--json", hemi->json, "Print one JSON object (keys in docs/cli.md)");
  hemi_cmd->callback([hemi, odd_order, even_order, odd_opt, even_opt] {
    if (odd_opt->count() > 0) hemi->odd_order = *odd_order;
    if (even_opt->count() > 0) hemi->even_order = *even_order;
    run_hemisphere(*hemi);
  });
}

}  // namespace prt::cli
