// The paper-table experiment through its library API on the tiny scene: the files it writes,
// their consistency, the provenance, the lossless check (which must also be able to fail), and
// failures that leave nothing behind.
#include "paper_table.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "lossless_check.h"
#include "paper_numbers.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "table_report.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, sep);) out.push_back(f);
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

struct Csv {
  std::vector<std::string> comments;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
};

// The table CSV has no quoted fields (scene names and numbers), so a plain split parses it.
Csv parse_csv(const std::string& text) {
  Csv csv;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);) {
    if (line.starts_with("#")) {
      csv.comments.push_back(line);
      continue;
    }
    const auto fields = split(line, ',');
    if (csv.header.empty()) {
      csv.header = fields;
      continue;
    }
    EXPECT_EQ(fields.size(), csv.header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < fields.size() && i < csv.header.size(); ++i)
      row[csv.header[i]] = fields[i];
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

double number(const std::map<std::string, std::string>& row, const std::string& key) {
  const auto it = row.find(key);
  EXPECT_NE(it, row.end()) << key;
  return it == row.end() ? NAN : std::stod(it->second);
}

class PaperTableTiny : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("prtlab_paper_table_" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    TableOptions o;
    o.scenes = {"tiny-sphere-plane"};
    o.repeats = 1;
    o.evaluation_lights = 2;
    o.cache_root = *dir_ / "cache";
    o.show_progress_bars = false;
    o.command_line = "prtlab experiment table1 --scenes tiny-sphere-plane (test)";
    o.on_progress = [](const std::string& line) { progress_lines_.push_back(line); };
    result_ = new TableResult(run_paper_table(PaperTable::kTable1, o));
    files_ = new std::vector<fs::path>(write_table_files(*result_, *dir_ / "out"));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete files_;
    delete result_;
    delete dir_;
  }
  static fs::path* dir_;
  static TableResult* result_;
  static std::vector<fs::path>* files_;
  static std::vector<std::string> progress_lines_;
};
fs::path* PaperTableTiny::dir_ = nullptr;
TableResult* PaperTableTiny::result_ = nullptr;
std::vector<fs::path>* PaperTableTiny::files_ = nullptr;
std::vector<std::string> PaperTableTiny::progress_lines_;

TEST_F(PaperTableTiny, WritesExactlyTheThreeFiles) {
  ASSERT_EQ(files_->size(), 3u);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(*dir_ / "out"))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"table1.csv", "table1.json", "table1.md"}));
}

TEST_F(PaperTableTiny, CsvParsesAndIsConsistent) {
  const Csv csv = parse_csv(slurp(*dir_ / "out" / "table1.csv"));
  EXPECT_EQ(csv.header, csv_columns());
  ASSERT_EQ(csv.rows.size(), 1u);
  const auto& r = csv.rows[0];
  EXPECT_EQ(r.at("scene"), "tiny-sphere-plane");
  const double vertices = number(r, "vertices");
  const double m = number(r, "local_directions"), n = number(r, "global_directions");
  EXPECT_EQ(m, 16);
  EXPECT_EQ(n, 6 * 8 * 8);
  EXPECT_GT(vertices, 0);
  const double nnz = number(r, "nnz");
  EXPECT_GT(nnz, 0);
  EXPECT_NEAR(number(r, "mflops"), 2 * nnz / 1e6, 1e-12);
  const double reduced = number(r, "reduced_mflops");
  EXPECT_GT(reduced, 0);
  EXPECT_LT(reduced, number(r, "mflops"));  // biclustering must save work on this scene
  EXPECT_NEAR(number(r, "computation_percent"), reduced / number(r, "mflops") * 100, 1e-9);
  EXPECT_NEAR(number(r, "dense_mb"), vertices * m * n / 1e6, 1e-9);
  EXPECT_NEAR(number(r, "data_percent"), number(r, "reduced_mb") / number(r, "dense_mb") * 100,
              1e-9);
  EXPECT_NEAR(number(r, "precompute_minutes"),
              number(r, "transfer_minutes") + number(r, "compress_minutes"), 1e-12);
  EXPECT_GT(number(r, "transfer_minutes"), 0);
  EXPECT_GT(number(r, "backend_ms_cpp"), 0);
  EXPECT_GT(number(r, "reference_ms_cpp"), 0);
  // No device and not a paper scene: explicit n/a, never 0 or blank.
  EXPECT_EQ(r.at("backend_ms_opencl"), "n/a");
  EXPECT_EQ(r.at("paper_nnz_millions"), "n/a");
  EXPECT_EQ(r.at("lossless"), "exact");
  EXPECT_EQ(number(r, "lossless_probe_mismatches"), 0);
  EXPECT_LT(number(r, "rel_l2_error_max"), 1e-6);
}

TEST_F(PaperTableTiny, LosslessCheckCoversEveryColumn) {
  const auto& c = result_->rows.at(0).lossless;
  EXPECT_TRUE(c.exact()) << c.verdict();
  EXPECT_TRUE(c.probe_applicable);
  EXPECT_EQ(c.probe_weight_base, 5);  // s = 2: counts 0..4 are base-5 digits
  EXPECT_EQ(c.columns_per_probe, 15);
  EXPECT_EQ(c.cpp.probes, (384u + 14) / 15);
  const std::size_t rows = result_->rows[0].vertices * 16;
  EXPECT_EQ(c.cpp.probe_values, c.cpp.probes * rows * 3);
  EXPECT_EQ(c.cpp.mismatches, 0u);
  EXPECT_LT(c.cpp.random_max_rel_error, kFloatRoundingBound);
  // The table's run has an OpenCL device where the machine has one: the device relight is
  // probed the same way.
  if (c.opencl) {
    EXPECT_EQ(c.opencl->probes, c.cpp.probes);
    EXPECT_EQ(c.opencl->mismatches, 0u);
    EXPECT_LT(c.opencl->random_max_rel_error, kFloatRoundingBound);
  }
}

TEST_F(PaperTableTiny, ProvenanceIsRecordedEverywhere) {
  const auto j = nlohmann::json::parse(slurp(*dir_ / "out" / "table1.json"));
  const auto& p = j.at("provenance");
  EXPECT_FALSE(p.at("git").get<std::string>().empty());
  EXPECT_EQ(p.at("git").get<std::string>().find("-dirty"), std::string::npos);
  EXPECT_TRUE(p.at("git_dirty").is_boolean());
  EXPECT_FALSE(p.at("build_type").get<std::string>().empty());
  EXPECT_FALSE(p.at("machine").at("cpu").get<std::string>().empty());
  EXPECT_GT(p.at("machine").at("cores").get<int>(), 0);
  EXPECT_GT(p.at("machine").at("memory_gib").get<double>(), 0.0);
  EXPECT_TRUE(p.at("opencl_device").is_null());
  // ISO 8601 UTC, "YYYY-MM-DDThh:mm:ssZ" (a pattern check without <regex>, whose GCC 12
  // headers warn under the asan preset).
  const std::string date = p.at("date_utc").get<std::string>();
  const std::string shape = "dddd-dd-ddTdd:dd:ddZ";
  ASSERT_EQ(date.size(), shape.size()) << date;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (shape[i] == 'd')
      EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(date[i]))) << date;
    else
      EXPECT_EQ(date[i], shape[i]) << date;
  }
  EXPECT_EQ(p.at("command"), "prtlab experiment table1 --scenes tiny-sphere-plane (test)");
  EXPECT_EQ(j.at("parameters").at("backend_parameters").at("seed"), "1");
  EXPECT_EQ(j.at("rows").size(), 1u);
  EXPECT_TRUE(j.at("rows")[0].at("lossless").at("exact").get<bool>());

  const std::string md = slurp(*dir_ / "out" / "table1.md");
  for (const char* s :
       {"## Provenance", "## How to reproduce", "## Notes",
        "prtlab experiment table1 --scenes tiny-sphere-plane", "exact reconstruction"})
    EXPECT_NE(md.find(s), std::string::npos) << s;
  EXPECT_NE(md.find(p.at("git").get<std::string>()), std::string::npos);

  const Csv csv = parse_csv(slurp(*dir_ / "out" / "table1.csv"));
  std::string comments;
  for (const auto& c : csv.comments) comments += c + "\n";
  for (const char* key : {"# git:", "# build:", "# machine:", "# opencl_device:", "# date:",
                          "# command:", "# parameters:"})
    EXPECT_NE(comments.find(key), std::string::npos) << key;
}

TEST_F(PaperTableTiny, ReportsProgressPerScene) {
  ASSERT_FALSE(progress_lines_.empty());
  for (const auto& line : progress_lines_)
    EXPECT_TRUE(line.starts_with("[table1 1/1] tiny-sphere-plane: ")) << line;
}

TEST(PaperTable, UnknownSceneFailsBeforeAnyStageAndWritesNothing) {
  const fs::path dir =
      fs::temp_directory_path() / ("prtlab_paper_table_bad_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  TableOptions o;
  o.scenes = {"tiny-sphere-plane", "no-such-scene"};
  o.cache_root = dir / "cache";
  o.show_progress_bars = false;
  try {
    (void)run_paper_table(PaperTable::kTable1, o);
    ADD_FAILURE() << "an unknown scene must throw";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scene 'no-such-scene' not found"), std::string::npos) << what;
    EXPECT_NE(what.find("bunny"), std::string::npos) << what;  // lists the known scenes
  }
  // Validation precedes the first stage: not even the valid scene's T was computed.
  EXPECT_FALSE(fs::exists(dir / "cache" / "transfer"));
  EXPECT_FALSE(fs::exists(dir));
  fs::remove_all(dir);
}

TEST(PaperTable, BadBackendParameterIsAParameterError) {
  TableOptions o;
  o.scenes = {"tiny-sphere-plane"};
  o.params = {{"no_such_key", "1"}};
  EXPECT_THROW((void)run_paper_table(PaperTable::kTable1, o), ParameterError);
  EXPECT_THROW((void)parse_paper_table("table3"), ParameterError);
}

// The transcription of the paper's numbers is checked against the paper's own arithmetic.
TEST(PaperNumbers, TablesAreSelfConsistent) {
  EXPECT_EQ(table_scenes(PaperTable::kTable1),
            (std::vector<std::string>{"bunny", "armor", "chair", "temple"}));
  EXPECT_EQ(table_scenes(PaperTable::kTable2),
            (std::vector<std::string>{"bunny", "bunny-12k", "bunny-48k"}));
  for (const auto table : {PaperTable::kTable1, PaperTable::kTable2})
    for (const auto& scene : table_scenes(table)) {
      const auto p = paper_row(table, scene);
      ASSERT_TRUE(p.has_value()) << scene;
      EXPECT_NEAR(p->mflops, 2 * p->nnz_millions, 0.15) << scene;
      EXPECT_NEAR(p->computation_percent, 100 * p->reduced_mflops / p->mflops, 0.1) << scene;
      EXPECT_NEAR(p->data_percent, 100 * p->reduced_mb / p->data_mb, 0.06) << scene;
    }
  EXPECT_FALSE(paper_row(PaperTable::kTable1, "bunny-12k").has_value());
  EXPECT_EQ(paper_row(PaperTable::kTable2, "bunny-48k")->precompute_minutes, 279);
}

// A backend that relights with a slightly wrong T (one count off by one) or with float noise:
// the check must catch the first and accept the second.
class PerturbedTransfer final : public CompressedTransfer {
 public:
  PerturbedTransfer(TransferMatrix t, float output_scale)
      : t_(std::move(t)), scale_(output_scale) {}
  std::string backend() const override { return "perturbed"; }
  StorageReport storage() const override { return {}; }
  double flops_per_relight() const override { return 2.0 * static_cast<double>(t_.nnz()); }
  double declared_error_bound() const override { return 0.0; }
  LightCoeffs project_light(const Cubemap& radiance) const override {
    return {"pixel", radiance.light_vector()};
  }
  void relight(const LightCoeffs& light, LocalRadiance& out) const override {
    out = relight_exact(t_, light.values);
    for (auto& v : out.values) v *= scale_;
  }
  std::unique_ptr<DeviceRelighter> upload(ClContext&, const ParamSet&) const override {
    return nullptr;
  }
  void save(ArchiveWriter&) const override {}

 private:
  TransferMatrix t_;
  float scale_;
};

// Exact in C++, but its device relight is the exact product of another matrix: a kernel bug
// that only the OpenCL probes can see. backend() names the uncompressed backend, whose device
// options upload_compressed validates.
class WrongOnTheDevice final : public CompressedTransfer {
 public:
  WrongOnTheDevice(TransferMatrix t, TransferMatrix on_device)
      : t_(std::move(t)),
        device_(CompressorRegistry::instance()
                    .create("uncompressed", {})
                    ->compress({on_device, nullptr, layout_, grid_}, Progress::null())) {}
  std::string backend() const override { return "uncompressed"; }
  StorageReport storage() const override { return {}; }
  double flops_per_relight() const override { return 2.0 * static_cast<double>(t_.nnz()); }
  double declared_error_bound() const override { return 0.0; }
  LightCoeffs project_light(const Cubemap& radiance) const override {
    return {"pixel", radiance.light_vector()};
  }
  void relight(const LightCoeffs& light, LocalRadiance& out) const override {
    out = relight_exact(t_, light.values);
  }
  std::unique_ptr<DeviceRelighter> upload(ClContext& ctx, const ParamSet& o) const override {
    return device_->upload(ctx, o);
  }
  void save(ArchiveWriter&) const override {}

 private:
  TransferMatrix t_;
  CubemapLayout layout_{RandomTransferSpec{}.resolution};
  HemisphereGrid grid_{RandomTransferSpec{}.grid_side};
  std::unique_ptr<CompressedTransfer> device_;
};

TransferMatrix with_count_changed(const TransferMatrix& t, std::size_t entry) {
  std::vector<std::uint32_t> offsets(t.row_offsets().begin(), t.row_offsets().end());
  std::vector<std::uint32_t> cols(t.nnz());
  for (std::size_t i = 0; i < t.nnz(); ++i) cols[i] = t.column(i);
  std::vector<std::uint8_t> counts(t.counts().begin(), t.counts().end());
  counts[entry] = counts[entry] == 1 ? 2 : static_cast<std::uint8_t>(counts[entry] - 1);
  return TransferMatrix::from_csr(t.vertex_count(), t.local_count(), static_cast<int>(t.cols()),
                                  t.supersampling(), std::move(offsets), cols, std::move(counts));
}

TEST(LosslessCheck, CatchesOneWrongCountAndToleratesFloatRounding) {
  RandomTransferSpec spec;  // 16 vertices, M = 16, N = 384, s = 2
  const TransferMatrix t = random_transfer(7, spec);
  ASSERT_GT(t.nnz(), 100u);

  const PerturbedTransfer exact(t, 1.0f);
  const auto ok = check_lossless(exact, t, spec.resolution);
  EXPECT_TRUE(ok.exact()) << ok.verdict();
  EXPECT_EQ(ok.cpp.max_count_error, 0.0);
  EXPECT_FALSE(ok.opencl.has_value()) << "no context given: C++ only";

  const PerturbedTransfer rounded(t, 1.0f + 4e-7f);  // a few float ulps on every value
  const auto near = check_lossless(rounded, t, spec.resolution);
  EXPECT_TRUE(near.exact()) << near.verdict();
  EXPECT_GT(near.cpp.random_max_rel_error, 0.0);

  const PerturbedTransfer wrong(with_count_changed(t, t.nnz() / 2), 1.0f);
  const auto bad = check_lossless(wrong, t, spec.resolution);
  EXPECT_FALSE(bad.exact());
  EXPECT_EQ(bad.cpp.mismatches, 1u);  // one entry: one row, one channel of one probe
  // A count off by one at digit i of a probe shows as (s^2 + 1)^i = 5^i code units.
  const double digit = std::log(bad.cpp.max_count_error) / std::log(5.0);
  EXPECT_NEAR(digit, std::round(digit), 1e-9) << bad.cpp.max_count_error;
  EXPECT_GT(bad.cpp.random_max_rel_error, kFloatRoundingBound);
  EXPECT_NE(bad.verdict().find("NOT exact"), std::string::npos);
}

TEST(LosslessCheck, BiclusterBackendIsExactOnARandomTransfer) {
  RandomTransferSpec spec;
  spec.density = 0.3;
  const TransferMatrix t = random_transfer(11, spec);
  const CubemapLayout layout(spec.resolution);
  const HemisphereGrid grid(spec.grid_side);
  const TransferInput input{t, nullptr, layout, grid};
  const auto ct =
      CompressorRegistry::instance().create(kTableBackend, {})->compress(input, Progress::null());
  const auto c = check_lossless(*ct, t, spec.resolution, {.device = default_context()});
  EXPECT_TRUE(c.exact()) << c.verdict();
  EXPECT_EQ(c.cpp.mismatches, 0u);
  if (c.opencl) {
    EXPECT_EQ(c.opencl->mismatches, 0u);
  }
}

TEST(LosslessCheck, ProbesTheOpenClRelightToo) {
  ClContext* ctx = default_context();
  if (!ctx) GTEST_SKIP() << "no OpenCL device: the device probes cannot run here";
  RandomTransferSpec spec;
  const TransferMatrix t = random_transfer(7, spec);
  const WrongOnTheDevice ct(t, with_count_changed(t, t.nnz() / 3));
  const auto cpp_only = check_lossless(ct, t, spec.resolution);
  EXPECT_TRUE(cpp_only.exact()) << "the C++ path is exact: " << cpp_only.verdict();
  const auto c = check_lossless(ct, t, spec.resolution, {.device = ctx});
  ASSERT_TRUE(c.opencl.has_value());
  EXPECT_FALSE(c.exact());
  EXPECT_EQ(c.cpp.mismatches, 0u);
  EXPECT_EQ(c.opencl->mismatches, 1u);
  EXPECT_NE(c.verdict().find("OpenCL"), std::string::npos) << c.verdict();
  EXPECT_EQ(c.device, ctx->info().label());
}

}  // namespace
}  // namespace prt::experiments
