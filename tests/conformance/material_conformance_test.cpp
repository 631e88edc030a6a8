// The material conformance suite: every registered material backend x a few small synthetic
// BTFs, with no per-backend code. A material added to the registry (built in, or a plugin listed
// in PRTLAB_TEST_PLUGINS) is tested automatically.
//
// Checks, per material and BTF:
//   - the reflectance at every sample vs the full BTF (material_error) within the declared
//     bound (relative L2; a lossless result declares 0 and gets kLosslessTolerance for float
//     rounding, as relative L2 and as max-norm error); a backend registered as lossless must
//     declare 0 at its defaults; its sampling and light basis are the BTF's;
//   - a lossless pixel-bin material's interpolated vectors and shading (eval_lights, shade) vs
//     the full BTF's (Btf::eval_lights, Btf::shade), both texel filters;
//   - the OpenCL evaluation (the shading program's view-cache kernel running the material's
//     source, evaluate_materials_on_device) vs eval_lights within kDeviceTolerance, both texel
//     filters, over every combination of the backend's device options, on two parts of which
//     the second has another BTF (part tables, offsets);
//   - save/load round trip: same backend, storage, FLOPs, bound, basis, sampling and
//     bit-identical reflectance and vectors; saving the loaded material again gives the same
//     bytes;
//   - storage and FLOPs positive, the storage total consistent with the saved file;
//   - determinism: two compressions with the same seed are bit-identical;
//   - per backend: an unknown parameter and every out-of-range value are ParameterErrors.
//
// Plugins: PRTLAB_TEST_PLUGINS=/path/a.so:/path/b.so loads them before the tests are generated
// (as tests/conformance/conformance_test.cpp does for transfer compressors).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/device_material_eval.h"
#include "prtlab/storage/archive.h"
#include "support/conformance_helpers.h"
#include "support/material_queries.h"
#include "support/temp_dir.h"
#include "support/test_plugins.h"

namespace prt::conformance {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache_root = prt::testing::use_private_cache("material_conformance");

// A vector b(u, e, .) is a weighted sum of at most 16 stored vectors with weights summing to 1,
// so float rounding stays below 16 * 2^-24 of the largest value; 1e-6 leaves margin without
// hiding a wrong sample (one wrong view weight changes a value by about 1e-2 of the maximum).
constexpr double kLosslessTolerance = 1e-6;
constexpr double kDeviceTolerance = 1e-5;
// As in the transfer suite: framing and metadata beside the sections.
constexpr std::uint64_t kFileUnderAllowance = 64;
constexpr std::uint64_t kFileOverheadFixed = 8 * 1024;
constexpr double kFileOverheadRelative = 0.01;

// ---- plugins and the generated tests' parameters ----

using testing::PluginLoad;

const PluginLoad& plugins() {
  return testing::test_plugins();
}

std::vector<std::string> material_names() {
  (void)plugins();
  return MaterialRegistry::instance().names();
}

// The synthetic BTFs: small, each with something the others lack.
struct BtfCase {
  std::string name;
  std::string material;
  int resolution, view_side, light_side;
  const char* why;
};
const std::vector<BtfCase>& btf_cases() {
  static const std::vector<BtfCase> cases = {
      {"checker_s4", "checker", 8, 6, 4, "meso-structure, glossy squares, M = 16"},
      {"bumps_s5_odd", "bumps", 5, 4, 5,
       "odd resolution and odd light side: M = 25, a 3-float tail past the 12-float chunks"},
      {"lambert_s3", "lambert", 4, 3, 3, "view independent (one stored view per texel), M = 9"},
  };
  return cases;
}

std::shared_ptr<const Btf> case_btf(const std::string& name) {
  static std::map<std::string, std::shared_ptr<const Btf>> done;
  auto& b = done[name];
  if (!b) {
    const auto it = std::find_if(btf_cases().begin(), btf_cases().end(),
                                 [&](const BtfCase& c) { return c.name == name; });
    PRT_CHECK(it != btf_cases().end(), "no BTF case {}", name);
    BtfParams p;
    p.resolution = it->resolution;
    p.view_side = it->view_side;
    p.light_side = it->light_side;
    p.supersampling = 1;
    p.geometry_grid = 32;
    b = std::make_shared<const Btf>(generate_btf(make_btf_material(it->material, 32), p));
  }
  return b;
}

struct CaseParam {
  std::string material;
  std::string btf;
};
void PrintTo(const CaseParam& p, std::ostream* os) {
  *os << p.material << " x " << p.btf;
}

std::vector<CaseParam> all_case_params() {
  std::vector<CaseParam> out;
  for (const auto& m : material_names())
    for (const auto& c : btf_cases()) out.push_back({m, c.name});
  return out;
}

std::string sanitize(std::string s) {
  return testing::sanitize_name(std::move(s));
}

// ---- helpers ----

using Params = std::map<std::string, std::string>;

std::shared_ptr<const CompressedMaterial> compress(const std::string& backend,
                                                   std::shared_ptr<const Btf> btf,
                                                   const Params& params = {}) {
  return compress_material(backend, params, std::move(btf));
}

std::vector<Rgb> cpp_vectors(std::span<const CompressedMaterial* const> parts,
                             std::span<const MaterialQuery> qs, TexelFilter filter) {
  const auto dim = static_cast<std::size_t>(parts.front()->light_basis().dim);
  std::vector<Rgb> out(qs.size() * dim);
  for (std::size_t i = 0; i < qs.size(); ++i)
    parts[static_cast<std::size_t>(qs[i].part)]->eval_lights(
        qs[i].uv, qs[i].view_local, std::span<Rgb>(out).subspan(i * dim, dim), filter);
  return out;
}

// Every reflectance sample of a material, in (texel, view, light) order.
std::vector<Rgb> all_samples(const CompressedMaterial& m) {
  const MaterialSampling s = m.sampling();
  std::vector<Rgb> out;
  out.reserve(static_cast<std::size_t>(s.texel_count()) * s.view_count() * s.light_count());
  for (int t = 0; t < s.texel_count(); ++t)
    for (int v = 0; v < s.view_count(); ++v)
      for (int j = 0; j < s.light_count(); ++j) out.push_back(m.reflectance(t, v, j));
  return out;
}

bool bit_identical(std::span<const Rgb> a, std::span<const Rgb> b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Rgb)) == 0);
}

using testing::same_storage;

std::vector<char> file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct TempFile : testing::ScratchFile {
  explicit TempFile(const std::string& stem) : ScratchFile(g_cache_root, stem) {}
};

// Every combination of a material's device options (choices, bools, integer range ends and
// default), as the transfer suite does.
std::vector<Params> device_param_sets(const MaterialEntry& entry) {
  return testing::device_option_sets(entry.device_params);
}

// ---- per material x BTF ----

class MaterialConformance : public ::testing::TestWithParam<CaseParam> {
 protected:
  void SetUp() override {
    entry_ = &MaterialRegistry::instance().get(GetParam().material);
    btf_ = case_btf(GetParam().btf);
    trace_ = std::make_unique<::testing::ScopedTrace>(
        __FILE__, __LINE__, "material " + GetParam().material + ", BTF " + GetParam().btf);
  }
  const MaterialEntry& entry() const { return *entry_; }
  const std::string& backend() const { return GetParam().material; }
  const Btf& btf() const { return *btf_; }
  const CompressedMaterial& compressed() {
    if (!compressed_) compressed_ = compress(backend(), btf_);
    return *compressed_;
  }
  std::shared_ptr<const Btf> btf_ptr() const { return btf_; }

 private:
  const MaterialEntry* entry_ = nullptr;
  std::shared_ptr<const Btf> btf_;
  std::unique_ptr<::testing::ScopedTrace> trace_;
  std::shared_ptr<const CompressedMaterial> compressed_;
};

TEST_P(MaterialConformance, ReflectanceMatchesTheFullBtfWithinTheDeclaredBound) {
  const CompressedMaterial& m = compressed();
  EXPECT_EQ(m.backend(), backend());
  EXPECT_EQ(m.sampling(), sampling_of(btf()));
  const MaterialLightBasis basis = m.light_basis();
  EXPECT_GT(basis.dim, 0);
  if (basis.basis == RadianceBasis::kPixel) {
    EXPECT_EQ(basis.dim, btf().light_count());
  }
  const double bound = m.declared_error_bound();
  ASSERT_TRUE(std::isfinite(bound) && bound >= 0) << "declared bound " << bound;
  if (entry().lossless) {
    EXPECT_EQ(bound, 0.0) << "a material registered as lossless declares 0 at its defaults";
  }
  const MaterialError e = material_error(m, btf());
  EXPECT_EQ(e.samples, btf().value_count());
  EXPECT_LE(e.relative_l2, bound + kLosslessTolerance) << "declared bound " << bound;
  if (bound == 0.0) {
    const double peak =
        e.reference_l2 > 0 ? *std::max_element(btf().data().begin(), btf().data().end()) : 1.0;
    EXPECT_LE(e.max_abs, kLosslessTolerance * peak);
  }
}

TEST_P(MaterialConformance, LosslessVectorsAndShadingEqualTheFullBtfs) {
  const CompressedMaterial& m = compressed();
  if (m.declared_error_bound() != 0.0 || m.light_basis().basis != RadianceBasis::kPixel)
    GTEST_SKIP() << "lossy or not in pixel bins: compared at the samples only";
  const auto qs = testing::material_queries(1, 3);
  const auto dim = static_cast<std::size_t>(m.light_basis().dim);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 3.0f);
  std::vector<Rgb> light(dim);
  for (auto& l : light) l = Rgb(u(rng), u(rng), u(rng));
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    SCOPED_TRACE(filter == TexelFilter::kNearest ? "nearest" : "bilinear");
    std::vector<Rgb> a(dim), b(dim), shaded_a, shaded_b;
    double worst = 0;
    for (const auto& q : qs) {
      m.eval_lights(q.uv, q.view_local, a, filter);
      btf().eval_lights(q.uv, q.view_local, b, filter);
      worst = std::max(worst, testing::max_relative_rgb(a, b));
      shaded_a.push_back(m.shade(q.uv, q.view_local, light, filter));
      shaded_b.push_back(btf().shade(q.uv, q.view_local, light, filter));
    }
    EXPECT_LE(worst, kLosslessTolerance) << "eval_lights vs Btf::eval_lights";
    EXPECT_LE(testing::max_relative_rgb(shaded_a, shaded_b), kLosslessTolerance)
        << "shade vs Btf::shade";
  }
}

TEST_P(MaterialConformance, OpenClMatchesTheCppEvaluation) {
  ClContext* ctx = default_context();
  if (ctx == nullptr)
    GTEST_SKIP() << "no OpenCL device on this machine: the device path is not tested here";
  // Two parts with different BTFs of the same light side: part tables and offsets matter.
  const auto other = std::make_shared<const Btf>([&] {
    BtfParams p;
    p.resolution = 3;
    p.view_side = btf().view_side();
    p.light_side = btf().light_side();
    p.supersampling = 1;
    p.geometry_grid = 32;
    return generate_btf(make_btf_material("rings", 32), p);
  }());
  const auto a = compress(backend(), btf_ptr()), b = compress(backend(), other);
  const std::vector<const CompressedMaterial*> parts = {a.get(), b.get()};
  {
    const auto device = upload_materials(*ctx, parts);
    EXPECT_GT(device->device_bytes(), 0u);
    for (std::size_t p = 0; p < parts.size(); ++p)
      EXPECT_GT(device->bytes_per_hit(p, TexelFilter::kNearest), 0u);
    EXPECT_FALSE(device->source().empty());
  }
  const auto qs = testing::material_queries(2, 5);
  for (const Params& options : device_param_sets(entry())) {
    for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
      SCOPED_TRACE(::testing::Message()
                   << (filter == TexelFilter::kNearest ? "nearest" : "bilinear") << ", "
                   << options.size() << " device options, " << ctx->info().label());
      const auto gpu = evaluate_materials_on_device(*ctx, parts, qs, filter, options);
      const auto cpp = cpp_vectors(parts, qs, filter);
      ASSERT_EQ(gpu.size(), cpp.size());
      EXPECT_LE(testing::max_relative_rgb(gpu, cpp), kDeviceTolerance);
    }
  }
}

TEST_P(MaterialConformance, SaveLoadRoundTripIsIdentical) {
  const CompressedMaterial& m = compressed();
  TempFile file(backend() + "_" + GetParam().btf), again(backend() + "_" + GetParam().btf + "_2");
  save_material(m, file.path);
  const auto loaded = load_material(file.path);
  ASSERT_NE(loaded, nullptr);
  EXPECT_EQ(loaded->backend(), m.backend());
  EXPECT_TRUE(same_storage(loaded->storage(), m.storage()));
  EXPECT_EQ(loaded->flops_per_pixel(), m.flops_per_pixel());
  EXPECT_EQ(loaded->declared_error_bound(), m.declared_error_bound());
  EXPECT_EQ(loaded->light_basis(), m.light_basis());
  EXPECT_EQ(loaded->sampling(), m.sampling());
  EXPECT_TRUE(bit_identical(all_samples(*loaded), all_samples(m)))
      << "reflectance differs after save/load";
  const std::vector<const CompressedMaterial*> before = {&m}, after = {loaded.get()};
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear})
    EXPECT_TRUE(bit_identical(cpp_vectors(after, testing::material_queries(1, 7), filter),
                              cpp_vectors(before, testing::material_queries(1, 7), filter)))
        << "interpolated vectors differ after save/load";
  save_material(*loaded, again.path);
  EXPECT_TRUE(file_bytes(file.path) == file_bytes(again.path))
      << "saving the loaded material gives other bytes";
}

TEST_P(MaterialConformance, StorageAndFlopsArePositiveAndMatchTheSavedFile) {
  const CompressedMaterial& m = compressed();
  const StorageReport report = m.storage();
  ASSERT_FALSE(report.components.empty());
  std::set<std::string> names;
  for (const auto& c : report.components) {
    EXPECT_FALSE(c.name.empty());
    EXPECT_FALSE(c.layout.empty()) << "component " << c.name << " documents no byte layout";
    EXPECT_TRUE(names.insert(c.name).second) << "component " << c.name << " listed twice";
  }
  const std::uint64_t total = report.total_bytes();
  EXPECT_GT(total, 0u);
  EXPECT_GT(m.flops_per_pixel(), 0.0);
  EXPECT_TRUE(std::isfinite(m.flops_per_pixel()));

  TempFile file(backend() + "_" + GetParam().btf + "_size");
  save_material(m, file.path);
  const std::uint64_t size = fs::file_size(file.path);
  const ArchiveReader archive = ArchiveReader::open(file.path);
  std::uint64_t payload = 0;
  for (const auto& s : archive.sections()) payload += s.bytes;
  SCOPED_TRACE(::testing::Message() << "storage total " << total << " B, file " << size
                                    << " B, section payloads " << payload << " B");
  EXPECT_GE(payload + kFileUnderAllowance, total)
      << "the report counts bytes the file does not hold";
  EXPECT_LE(static_cast<double>(size), static_cast<double>(total) * (1 + kFileOverheadRelative) +
                                           static_cast<double>(kFileOverheadFixed))
      << "the file holds much more than the report counts";
  EXPECT_EQ(archive.meta_value<std::uint64_t>("storage_bytes"), total);
  EXPECT_EQ(archive.meta_value<std::string>("backend"), backend());
}

TEST_P(MaterialConformance, SameSeedGivesBitIdenticalMaterials) {
  const Params seeded{{"seed", "7"}};
  const auto a = compress(backend(), btf_ptr(), seeded);
  const auto b = compress(backend(), btf_ptr(), seeded);
  EXPECT_TRUE(same_storage(a->storage(), b->storage()));
  EXPECT_EQ(a->flops_per_pixel(), b->flops_per_pixel());
  EXPECT_TRUE(bit_identical(all_samples(*a), all_samples(*b)));
}

INSTANTIATE_TEST_SUITE_P(Registry, MaterialConformance, ::testing::ValuesIn(all_case_params()),
                         [](const ::testing::TestParamInfo<CaseParam>& p) {
                           return sanitize(p.param.material) + "_" + p.param.btf;
                         });

// ---- per material ----

class MaterialConformanceParams : public ::testing::TestWithParam<std::string> {};

TEST_P(MaterialConformanceParams, DefaultsConstructAndEveryKeyIsDocumented) {
  const auto& entry = MaterialRegistry::instance().get(GetParam());
  EXPECT_FALSE(entry.description.empty());
  for (const auto& spec : entry.params) EXPECT_FALSE(spec.doc.empty()) << "parameter " << spec.key;
  for (const auto& spec : entry.device_params)
    EXPECT_FALSE(spec.doc.empty()) << "device option " << spec.key;
  EXPECT_NE(MaterialRegistry::instance().create(GetParam(), {}), nullptr);
}

TEST_P(MaterialConformanceParams, RejectsAnUnknownParameter) {
  try {
    MaterialRegistry::instance().create(GetParam(), {{"no_such_parameter", "1"}});
    FAIL() << "accepted an unknown parameter";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_parameter"), std::string::npos) << e.what();
  }
  EXPECT_THROW(MaterialRegistry::instance().device_options(GetParam(), {{"no_such_option", "1"}}),
               ParameterError);
}

TEST_P(MaterialConformanceParams, RejectsEveryValueOutsideItsRange) {
  const auto& entry = MaterialRegistry::instance().get(GetParam());
  std::vector<ParamSpec> specs = entry.params;
  for (const auto& s : shared_param_specs()) specs.push_back(s);
  int checked = 0;
  for (const auto& spec : specs) {
    std::vector<std::string> bad;
    if (spec.type == prt::ParamType::kInt) {
      if (spec.min) bad.push_back(fmt::format("{}", static_cast<long long>(*spec.min) - 1));
      if (spec.max) bad.push_back(fmt::format("{}", static_cast<long long>(*spec.max) + 1));
      bad.push_back("not-a-number");
    } else if (spec.type == prt::ParamType::kReal) {
      if (spec.min)
        bad.push_back(fmt::format("{}", *spec.min - std::max(1.0, std::abs(*spec.min))));
      if (spec.max)
        bad.push_back(fmt::format("{}", *spec.max + std::max(1.0, std::abs(*spec.max))));
      bad.push_back("not-a-number");
    } else if ((spec.type == prt::ParamType::kString && !spec.choices.empty()) ||
               spec.type == prt::ParamType::kEnum) {
      bad.push_back("not-one-of-the-choices");
    } else if (spec.type == prt::ParamType::kBool) {
      bad.push_back("maybe");
    }
    for (const auto& value : bad) {
      ++checked;
      EXPECT_THROW(MaterialRegistry::instance().create(GetParam(), {{spec.key, value}}),
                   ParameterError)
          << spec.key << "=" << value << " was accepted";
    }
  }
  EXPECT_GT(checked, 0) << "the shared 'seed' parameter alone has a range";
}

INSTANTIATE_TEST_SUITE_P(Registry, MaterialConformanceParams, ::testing::ValuesIn(material_names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           return sanitize(p.param);
                         });

// ---- the suite itself ----

TEST(MaterialConformanceSuite, EveryListedPluginLoadedAndIsCovered) {
  const PluginLoad& load = plugins();
  for (const auto& e : load.errors) ADD_FAILURE() << "PRTLAB_TEST_PLUGINS: " << e;
  const auto names = material_names();
  EXPECT_TRUE(std::count(names.begin(), names.end(), "full")) << "the built-in full material";
  if (!load.paths.empty()) {
    EXPECT_FALSE(load.names.empty()) << "the listed plugins registered nothing";
  }
  EXPECT_EQ(all_case_params().size(), names.size() * btf_cases().size());
}

TEST(MaterialConformanceSuite, BtfCasesAreWhatTheyClaim) {
  EXPECT_FALSE(case_btf("checker_s4")->view_independent());
  EXPECT_TRUE(case_btf("lambert_s3")->view_independent());
  EXPECT_EQ(case_btf("bumps_s5_odd")->light_count() * 3 % 12, 3);
  for (const auto& c : btf_cases()) {
    const auto b = case_btf(c.name);
    EXPECT_EQ(b->resolution(), c.resolution) << c.why;
    EXPECT_GT(*std::max_element(b->data().begin(), b->data().end()), 0.0f) << c.name;
  }
}

}  // namespace
}  // namespace prt::conformance
