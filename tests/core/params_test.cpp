#include "prtlab/compress/params.h"

#include <gtest/gtest.h>

#include "prtlab/base/error.h"

namespace prt {
namespace {

const std::vector<ParamSpec> kSpecs = {
    {"clusters", ParamType::kInt, "32", 1.0, 4096.0, {}, "number of clusters"},
    {"error", ParamType::kReal, "0", 0.0, 1.0, {}, "relative error budget"},
    {"lossy", ParamType::kBool, "false", {}, {}, {}, "drop residual terms"},
    {"mode",
     ParamType::kString,
     "static",
     {},
     {},
     {"static", "iterative", "adaptive"},
     "CPCA variant"},
};

TEST(Params, DefaultsAndGivenValues) {
  ParamSet p("cpca", kSpecs, {{"clusters", "64"}, {"mode", "adaptive"}});
  EXPECT_EQ(p.get_int("clusters"), 64);
  EXPECT_EQ(p.get_real("error"), 0.0);
  EXPECT_FALSE(p.get_bool("lossy"));
  EXPECT_EQ(p.get_string("mode"), "adaptive");
  EXPECT_EQ(p.get_int("seed"), 1);  // shared key
  EXPECT_TRUE(p.was_given("clusters"));
  EXPECT_FALSE(p.was_given("error"));
  EXPECT_EQ(p.canonical().at("clusters"), "64");
  EXPECT_EQ(p.canonical().at("lossy"), "false");
}

enum class Mode { kStatic, kIterative, kAdaptive };

TEST(Params, EnumValuesMapToTheirEnumeratorsAndOthersAreRefused) {
  const std::vector<ParamSpec> specs = {
      {"mode", ParamType::kEnum, "static", {}, {}, {"static", "iterative", "adaptive"}, "variant"}};
  auto read = [&](const std::map<std::string, std::string>& given) {
    return ParamSet("cpca", specs, given)
        .get_enum<Mode>("mode", {{"static", Mode::kStatic},
                                 {"iterative", Mode::kIterative},
                                 {"adaptive", Mode::kAdaptive}});
  };
  EXPECT_EQ(read({}), Mode::kStatic);
  EXPECT_EQ(read({{"mode", "adaptive"}}), Mode::kAdaptive);
  EXPECT_EQ(ParamSet("cpca", specs, {{"mode", "iterative"}}).get_string("mode"), "iterative");
  EXPECT_THROW(read({{"mode", "dynamic"}}), ParameterError);
  // A reader that forgets a choice is a bug of the reader, reported as such.
  EXPECT_THROW(ParamSet("cpca", specs, {{"mode", "adaptive"}})
                   .get_enum<Mode>("mode", {{"static", Mode::kStatic}}),
               Error);
  // An enum without choices is refused when the set is built.
  const std::vector<ParamSpec> empty = {{"mode", ParamType::kEnum, "x", {}, {}, {}, "variant"}};
  EXPECT_ANY_THROW(ParamSet("cpca", empty, {}));
  EXPECT_EQ(to_string(ParamType::kEnum), "enum");
}

TEST(Params, DeviceOptionsLeaveOutTheSharedParameters) {
  const std::vector<ParamSpec> specs = {
      {"opencl_x", ParamType::kEnum, "a", {}, {}, {"a", "b"}, "variant"}};
  EXPECT_NO_THROW(ParamSet("b", specs, {{"seed", "2"}}));
  EXPECT_THROW(ParamSet("b", specs, {{"seed", "2"}}, ParamSet::Shared::kExclude), ParameterError);
  EXPECT_EQ(ParamSet("b", specs, {}, ParamSet::Shared::kExclude).canonical().size(), 1u);
}

TEST(Params, UnknownKeyListsValidOnes) {
  try {
    ParamSet p("cpca", kSpecs, {{"clusterz", "3"}});
    FAIL() << "accepted an unknown key";
  } catch (const ParameterError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("clusterz"), std::string::npos) << msg;
    EXPECT_NE(msg.find("clusters"), std::string::npos) << msg;
    EXPECT_NE(msg.find("number of clusters"), std::string::npos) << msg;
    EXPECT_NE(msg.find("seed"), std::string::npos) << msg;
  }
}

TEST(Params, BadValuesAreRejected) {
  EXPECT_THROW(ParamSet("x", kSpecs, {{"clusters", "0"}}), ParameterError);     // below min
  EXPECT_THROW(ParamSet("x", kSpecs, {{"clusters", "5000"}}), ParameterError);  // above max
  EXPECT_THROW(ParamSet("x", kSpecs, {{"clusters", "3.5"}}), ParameterError);   // not an int
  EXPECT_THROW(ParamSet("x", kSpecs, {{"error", "abc"}}), ParameterError);
  EXPECT_THROW(ParamSet("x", kSpecs, {{"error", "nan"}}), ParameterError);
  EXPECT_THROW(ParamSet("x", kSpecs, {{"lossy", "maybe"}}), ParameterError);
  EXPECT_THROW(ParamSet("x", kSpecs, {{"mode", "fancy"}}), ParameterError);
  EXPECT_NO_THROW(ParamSet("x", kSpecs, {{"error", "1e-2"}, {"lossy", "on"}}));
}

TEST(Params, ReadingAsTheWrongTypeIsAnInternalError) {
  ParamSet p("x", kSpecs, {});
  EXPECT_THROW(p.get_real("clusters"), Error);
  EXPECT_THROW(p.get_int("undeclared"), Error);
}

TEST(Params, ParseAssignments) {
  const std::vector<std::string> ok = {"a=1", "b=x=y", "c="};
  auto m = ParamSet::parse_assignments(ok);
  EXPECT_EQ(m.at("a"), "1");
  EXPECT_EQ(m.at("b"), "x=y");
  EXPECT_EQ(m.at("c"), "");
  const std::vector<std::string> bad1 = {"novalue"};
  const std::vector<std::string> bad2 = {"=3"};
  const std::vector<std::string> twice = {"a=1", "a=2"};
  EXPECT_THROW(ParamSet::parse_assignments(bad1), ParameterError);
  EXPECT_THROW(ParamSet::parse_assignments(bad2), ParameterError);
  EXPECT_THROW(ParamSet::parse_assignments(twice), ParameterError);
}

}  // namespace
}  // namespace prt
