// Material tables (experiments/material_table.h): the kind is recognised, variants are read,
// and a bad file is refused before any BTF is generated, with an error naming the file and
// the problem (unknown keys, a key that slipped into a table, bad labels, unknown backends or
// parameters, bad angles).
#include "material_table.h"

#include <gtest/gtest.h>

#include <fstream>

#include "prtlab/base/error.h"
#include "support/temp_dir.h"

namespace prt::experiments {
namespace {

const char* kGood = R"(name = "t"
kind = "material_table"
btfs = ["checker"]
resolution = 4
view_side = 2
light_side = 2
[[materials]]
label = "a"
backend = "cmf"
params = { clusters = 0 }
[variant.quick]
resolution = 2
)";

std::filesystem::path write(const testing::TempDir& dir, const std::string& text) {
  const auto p = dir.path() / "table.toml";
  std::ofstream(p) << text;
  return p;
}

void expect_refused(const std::string& text, const std::string& needle) {
  testing::TempDir dir("material_table");
  const auto file = write(dir, text);
  MaterialTableOptions o;
  o.out_root = dir.path() / "out";
  o.show_progress = false;
  try {
    (void)run_material_table(file, o);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("table.toml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "out")) << "nothing is written for a bad file";
}

TEST(MaterialTable, KindAndVariantsAreRead) {
  testing::TempDir dir("material_table");
  const auto file = write(dir, kGood);
  EXPECT_TRUE(is_material_table(file));
  EXPECT_EQ(material_table_variants(file), std::vector<std::string>{"quick"});
  const auto other = dir.path() / "sweep.toml";
  std::ofstream(other) << "name = \"x\"\nkind = \"sweep\"\n";
  EXPECT_FALSE(is_material_table(other));
}

TEST(MaterialTable, BadFilesAreRefusedNamingTheProblem) {
  const std::string good = kGood;
  expect_refused("typo = 1\n" + good, "unknown key 'typo'");
  expect_refused(good + "[image]\nscene = \"bunny\"\npaper_source = \"x\"\n",
                 "image: unknown key 'paper_source'");
  expect_refused(std::string(kGood).replace(good.find("label = \"a\""), 11, "label = \"a/b\""),
                 "label 'a/b'");
  expect_refused(good + "[[materials]]\nlabel = \"a\"\nbackend = \"hf\"\n", "used twice");
  expect_refused(
      std::string(kGood).replace(good.find("backend = \"cmf\""), 15, "backend = \"nope\""),
      "unknown material backend 'nope'");
  expect_refused(std::string(kGood).replace(good.find("clusters = 0"), 12, "clusterz = 0"),
                 "materials 'a'");
  expect_refused(
      std::string(kGood).replace(good.find("btfs = [\"checker\"]"), 18, "btfs = [\"chequer\"]"),
      "'chequer' is not a BTF");
  expect_refused("tile_polar_deg = [120]\n" + good, "tile_polar_deg");
}

}  // namespace
}  // namespace prt::experiments
