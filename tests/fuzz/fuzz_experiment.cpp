// Fuzz target: the experiment-file parsers (experiment_spec.h, run_plan.h, material_table.h,
// stability_suite.h). The input is the TOML file: it is parsed at its top level and with every
// variant it declares, as `prtlab experiment run` does before it runs, and a transfer experiment's
// grid is counted against the default point budget. Nothing runs: no scene is prepared and no map
// read.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "experiment_spec.h"
#include "fuzz_support.h"
#include "material_table.h"
#include "prtlab/compress/compressor_registry.h"
#include "run_plan.h"
#include "stability_suite.h"

namespace {

// `prtlab experiment run`'s default --max-points.
constexpr std::size_t kDefaultMaxPoints = 2000;

void check(const std::filesystem::path& file, const std::string& variant) {
  namespace ex = prt::experiments;
  const std::string kind = ex::declared_kind(file);
  if (kind == "material_table") return ex::check_material_table(file, variant);
  if (kind == "stability") return ex::check_stability_suite(file, variant);
  const auto spec =
      ex::parse_experiment(file, variant, prt::CompressorRegistry::instance().names());
  (void)ex::planned_points(spec);
  ex::check_point_budget(spec, kDefaultMaxPoints);
  (void)ex::to_json(spec).dump();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::fuzz::InputFile file(".toml");
  const auto& path = file.write(std::span(data, size));
  prt::fuzz::run([&] { check(path, ""); });
  // Each variant on its own: one refused variant must not hide another's crash.
  for (const std::string& v : prt::experiments::declared_variants(path))
    prt::fuzz::run([&] { check(path, v); });
  return 0;
}
