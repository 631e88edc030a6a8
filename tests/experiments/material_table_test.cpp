// Material tables (experiments/material_table.h): the kind is recognised, variants are read,
// and a bad file is refused before any BTF is generated, with an error naming the file and
// the problem (unknown keys, a key that slipped into a table, bad labels, unknown backends or
// parameters, bad angles); a run on a tiny BTF and scene writes every error measure
// (material_error.h's, the rendered image's SSIM and tone-mapped RMSE) into result.json,
// table.csv and the README.
#include "material_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

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

TEST(MaterialTable, ARunWritesEveryErrorMeasure) {
  testing::TempDir dir("material_table");
  const auto file = write(dir, R"(name = "t"
kind = "material_table"
btfs = ["checker", "weave"]
resolution = 4
view_side = 2
light_side = 4
tile_polar_deg = [0]
[[materials]]
label = "a"
backend = "cmf"
params = { clusters = 0, refine = 0, halfway = "mean" }
[image]
scene = "tiny-sphere-plane"
btf = "checker"
width = 16
height = 12
)");
  MaterialTableOptions o;
  o.out_root = dir.path() / "out";
  o.show_progress = false;
  const nlohmann::json r = run_material_table(file, o);
  const std::filesystem::path folder = r.at("folder").get<std::string>();
  ASSERT_EQ(r.at("rows").size(), 2u);
  for (const auto& row : r.at("rows")) {
    for (const char* key :
         {"rel_l2", "average_relative", "average_relative_worst_abrdf", "average_relative_floored",
          "average_abs", "cosine_l2", "white_light_l2"}) {
      ASSERT_TRUE(row.at(key).is_number()) << key;
      EXPECT_GE(row.at(key).get<double>(), 0.0) << key;
    }
    EXPECT_GE(row.at("average_relative_worst_abrdf").get<double>(),
              row.at("average_relative").get<double>());
    // Each floored term is at most the unfloored one, so with no zero sample the mean is too.
    if (row.at("zero_samples").get<std::uint64_t>() == 0) {
      EXPECT_LE(row.at("average_relative_floored").get<double>(),
                row.at("average_relative").get<double>() * (1 + 1e-12));
    }
  }
  ASSERT_EQ(r.at("images").size(), 2u);  // full, a
  const auto& img = r.at("images")[1];
  const double ssim = img.at("ssim").get<double>();
  EXPECT_GT(ssim, -1.0);
  EXPECT_LE(ssim, 1.0);
  EXPECT_GE(img.at("display_error").at("rmse").get<double>(), 0.0);
  EXPECT_LE(img.at("display_error").at("rmse").get<double>(), 1.0) << "display values in [0, 1]";

  std::ifstream csv(folder / "table.csv");
  std::string comment, header, checker, weave;
  std::getline(csv, comment);
  std::getline(csv, header);
  std::getline(csv, checker);
  std::getline(csv, weave);
  EXPECT_NE(header.find(",rel_l2,max_abs,average_relative,average_relative_worst_abrdf,"
                        "average_relative_floored,average_abs,zero_samples,cosine_l2,"
                        "white_light_l2,image_rel_l2,image_ssim,image_display_rmse"),
            std::string::npos)
      << header;
  const auto fields = [](const std::string& line) {
    return static_cast<int>(std::count(line.begin(), line.end(), ','));
  };
  EXPECT_EQ(fields(checker), fields(header));
  EXPECT_EQ(fields(weave), fields(header));
  EXPECT_NE(checker.substr(checker.size() - 2), ",,") << "the image BTF row has its image columns";
  EXPECT_EQ(weave.substr(weave.size() - 2), ",,") << "other BTFs' rows leave them empty";
  std::stringstream md;
  md << std::ifstream(folder / "README.md").rdbuf();
  for (const char* text : {"avg. rel. (Suykens)", "white-light L2", "| SSIM |", "display RMSE"})
    EXPECT_NE(md.str().find(text), std::string::npos) << text;
}

}  // namespace
}  // namespace prt::experiments
