// The conformance suite's accuracy checks can fail: for every registered lossy backend (the
// entries not registered as lossless, plugins of PRTLAB_TEST_PLUGINS included) the checks of
// accuracy_checks.h, which conformance_test.cpp runs, accept the backend's default compression
// of two cases and reject the same result with its C++ relight perturbed by 1 %
// (perturbed_transfer.h: every value times 1.01, or alternately times 1.01 and 0.99).
#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <memory>

#include "prtlab/compress/compressor_registry.h"
#include "support/accuracy_checks.h"
#include "support/conformance_helpers.h"
#include "support/perturbed_transfer.h"
#include "support/synthetic_cases.h"
#include "support/temp_dir.h"
#include "support/test_plugins.h"

namespace prt::conformance {
namespace {

[[maybe_unused]] const auto g_cache_root = prt::testing::use_private_cache("lossy_perturbation");

using testing::Perturbation;

// A real shadowed transfer and a random one with an empty vertex.
const char* const kCases[] = {"sphere_over_plane", "random_dense_s3"};

std::vector<std::string> lossy_backends() {
  (void)testing::test_plugins();
  std::vector<std::string> out;
  for (const auto& name : CompressorRegistry::instance().names())
    if (!CompressorRegistry::instance().get(name).lossless) out.push_back(name);
  return out;
}

std::unique_ptr<CompressedTransfer> compress(const std::string& backend, const CaseData& c) {
  const auto& entry = CompressorRegistry::instance().get(backend);
  return CompressorRegistry::instance()
      .create(backend, {})
      ->compress(c.input(entry), Progress::null());
}

class LossyPerturbation : public ::testing::TestWithParam<std::string> {};

// The backends of the papers: none has a proven bound to lean on, each is held to its model.
const char* const kPaperBackends[] = {"cpca", "cpca_sh", "haar", "sh_biscale", "srbf_cta"};

TEST_P(LossyPerturbation, AccuracyChecksAcceptTheBackendAndRejectItsRelightOffByOnePercent) {
  const std::string& backend = GetParam();
  const CompressorEntry& entry = CompressorRegistry::instance().get(backend);
  for (const char* name : kCases) {
    const CaseData& c = case_data(name);
    SCOPED_TRACE(c.description);
    const std::shared_ptr<const CompressedTransfer> ct = compress(backend, c);
    if (std::count(std::begin(kPaperBackends), std::end(kPaperBackends), backend)) {
      EXPECT_NE(stored_model(*ct), nullptr) << backend << " offers no stored model";
      EXPECT_TRUE(ct->expected_frobenius_error().has_value()) << backend;
    }
    for (std::size_t l = 0; l < c.lights.size(); ++l)
      EXPECT_TRUE(relight_within_declaration(*ct, entry, c, c.lights[l])) << "light " << l;
    EXPECT_TRUE(frobenius_within_declaration(*ct, entry, c));
    for (const Perturbation p : {Perturbation::kScale, Perturbation::kAlternating}) {
      SCOPED_TRACE(std::string("relight perturbed: ") + testing::to_string(p));
      const auto bad = testing::perturbed(ct, p);
      for (std::size_t l = 0; l < c.lights.size(); ++l) {
        const ::testing::AssertionResult r =
            relight_within_declaration(*bad, entry, c, c.lights[l]);
        EXPECT_FALSE(r) << "light " << l
                        << ": the relight check accepts a 1 % error: " << r.message();
      }
      const ::testing::AssertionResult f = frobenius_within_declaration(*bad, entry, c);
      EXPECT_FALSE(f) << "the Frobenius check accepts a 1 % error: " << f.message();
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, LossyPerturbation, ::testing::ValuesIn(lossy_backends()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           return testing::sanitize_name(p.param);
                         });

TEST(LossyPerturbationSuite, CoversThePapersLossyBackends) {
  const auto lossy = lossy_backends();
  for (const char* name : kPaperBackends)
    EXPECT_TRUE(std::count(lossy.begin(), lossy.end(), name)) << name << " is not registered lossy";
}

}  // namespace
}  // namespace prt::conformance
