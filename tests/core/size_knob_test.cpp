// Size knobs: resolve_size_knob() takes the range from the parameter unless narrowed and refuses
// every knob that does not fit its parameters; the registry refuses an entry with such a knob
// and stores the resolved range of one that fits.
#include "prtlab/compress/size_knob.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"

namespace prt {
namespace {

const std::vector<ParamSpec> kParams = {
    {"budget", ParamType::kReal, "0", 0.0, 1.0, {}, "an error budget"},
    {"clusters", ParamType::kInt, "8", 1.0, 256.0, {}, "a cluster count"},
    {"open", ParamType::kReal, "1", 0.0, std::nullopt, {}, "no upper bound"},
    {"exact", ParamType::kBool, "false", std::nullopt, std::nullopt, {}, "a switch"},
};

// The knob is refused with a ParameterError naming the backend and containing `reason`.
void expect_refused(const SizeKnob& knob, const std::string& reason) {
  try {
    resolve_size_knob("backend-x", knob, kParams);
    ADD_FAILURE() << "knob '" << knob.key << "' accepted; expected: " << reason;
  } catch (const ParameterError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(reason), std::string::npos) << "knob '" << knob.key << "': " << message;
    EXPECT_NE(message.find("backend-x"), std::string::npos) << message;
  }
}

TEST(SizeKnob, RangeDefaultsToTheParametersOwn) {
  const SizeKnob k = resolve_size_knob("backend-x", {.key = "clusters"}, kParams);
  EXPECT_EQ(k.min, 1.0);
  EXPECT_EQ(k.max, 256.0);
  EXPECT_EQ(k.direction, SizeKnob::Direction::kLargerIsMoreStorage);
  EXPECT_EQ(k.scale, SizeKnob::Scale::kLinear);
}

TEST(SizeKnob, ANarrowedRangeIsKeptAndMayOpenOneSide) {
  const SizeKnob k = resolve_size_knob("backend-x",
                                       {.key = "budget",
                                        .direction = SizeKnob::Direction::kLargerIsLessStorage,
                                        .min = 1e-3,
                                        .scale = SizeKnob::Scale::kLog},
                                       kParams);
  EXPECT_EQ(k.min, 1e-3);
  EXPECT_EQ(k.max, 1.0);
  EXPECT_EQ(k.direction, SizeKnob::Direction::kLargerIsLessStorage);
  const SizeKnob open = resolve_size_knob("backend-x", {.key = "open", .max = 4.0}, kParams);
  EXPECT_EQ(open.min, 0.0);
  EXPECT_EQ(open.max, 4.0);
}

TEST(SizeKnob, EveryKnobThatDoesNotFitIsRefusedWithItsReason) {
  expect_refused({.key = "no_such"}, "not one of the backend's parameters");
  expect_refused({.key = "seed"}, "not one of the backend's parameters");  // shared
  expect_refused({.key = "exact"}, "a bool parameter");
  expect_refused({.key = "open"}, "no bound on one side");
  expect_refused({.key = "budget", .min = -0.5}, "leaves the parameter's");
  expect_refused({.key = "clusters", .max = 512.0}, "leaves the parameter's");
  expect_refused({.key = "budget", .min = 0.5, .max = 0.5}, "empty range");
  expect_refused({.key = "budget", .min = 0.7, .max = 0.2}, "empty range");
  expect_refused({.key = "clusters", .min = 1.5}, "fractional end");
  expect_refused({.key = "budget", .scale = SizeKnob::Scale::kLog},
                 "log scale needs a positive minimum");
}

TEST(SizeKnob, DirectionAndScaleHaveStableNames) {
  EXPECT_EQ(to_string(SizeKnob::Direction::kLargerIsMoreStorage), "larger_is_more_storage");
  EXPECT_EQ(to_string(SizeKnob::Direction::kLargerIsLessStorage), "larger_is_less_storage");
  EXPECT_EQ(to_string(SizeKnob::Scale::kLinear), "linear");
  EXPECT_EQ(to_string(SizeKnob::Scale::kLog), "log");
}

CompressorEntry entry_with_knob(std::string name, SizeKnob knob) {
  CompressorEntry e;
  e.name = std::move(name);
  e.description = "test entry";
  e.params = kParams;
  e.size_knob = std::move(knob);
  e.create = [](const ParamSet&) -> std::unique_ptr<Compressor> { return nullptr; };
  e.load = [](const ArchiveReader&) -> std::unique_ptr<CompressedTransfer> { return nullptr; };
  return e;
}

TEST(SizeKnob, TheRegistryRefusesAnEntryWhoseKnobDoesNotFit) {
  auto& registry = CompressorRegistry::instance();
  EXPECT_THROW(registry.add(entry_with_knob("size-knob-bad", {.key = "exact"})), ParameterError);
  EXPECT_FALSE(registry.contains("size-knob-bad"));
}

TEST(SizeKnob, TheRegistryStoresTheResolvedRange) {
  auto& registry = CompressorRegistry::instance();
  registry.add(entry_with_knob("size-knob-good", {.key = "clusters", .min = 4.0}));
  const auto& knob = registry.get("size-knob-good").size_knob;
  ASSERT_TRUE(knob.has_value());
  EXPECT_EQ(knob->min, 4.0);
  EXPECT_EQ(knob->max, 256.0);
  registry.remove("size-knob-good");
}

TEST(SizeKnob, BuiltInBackendsDeclareTheirKnobs) {
  const auto& registry = CompressorRegistry::instance();
  const auto& bicluster = registry.get("bicluster").size_knob;
  ASSERT_TRUE(bicluster.has_value());
  EXPECT_EQ(bicluster->key, "error");
  EXPECT_EQ(bicluster->direction, SizeKnob::Direction::kLargerIsLessStorage);
  EXPECT_GT(*bicluster->min, 0.0) << "a log-scaled knob starts above 0";
  EXPECT_FALSE(registry.get("uncompressed").size_knob.has_value()) << "fixed size";
  EXPECT_EQ(registry.get("uncompressed").output_basis, RadianceBasis::kPixel);
}

}  // namespace
}  // namespace prt
