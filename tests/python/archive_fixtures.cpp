// Writes the archives the Python reader test (tests/python/test_archive_reader.py) opens, with
// the C++ side's view of them in expected.json: transfer matrices (u16 and u32 columns, with and
// without the SH section) with their exact double product under a fixed light, one compressed
// transfer per registered backend with every section's payload digest, and an archive holding
// every element type at its extremes.
//
// Usage: prtlab-python-fixtures <output folder>
#include <fmt/format.h>

#include <bit>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/sphere_over_plane.h"
#include "prtlab/base/progress.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/archive.h"
#include "prtlab/storage/content_hash.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_io.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::span<const std::byte> payload(const prt::ArchiveReader& r, const prt::SectionInfo& s) {
  using prt::ElementType;
  switch (s.type) {
    case ElementType::kUInt8:
      return std::as_bytes(r.view<std::uint8_t>(s.name));
    case ElementType::kInt8:
      return std::as_bytes(r.view<std::int8_t>(s.name));
    case ElementType::kUInt16:
      return std::as_bytes(r.view<std::uint16_t>(s.name));
    case ElementType::kInt16:
      return std::as_bytes(r.view<std::int16_t>(s.name));
    case ElementType::kUInt32:
      return std::as_bytes(r.view<std::uint32_t>(s.name));
    case ElementType::kInt32:
      return std::as_bytes(r.view<std::int32_t>(s.name));
    case ElementType::kUInt64:
      return std::as_bytes(r.view<std::uint64_t>(s.name));
    case ElementType::kInt64:
      return std::as_bytes(r.view<std::int64_t>(s.name));
    case ElementType::kFloat32:
      return std::as_bytes(r.view<float>(s.name));
    case ElementType::kFloat64:
      return std::as_bytes(r.view<double>(s.name));
  }
  throw std::logic_error("unknown element type");
}

// What the C++ reader sees in a written file: its checksum and each section's type, count and
// payload digest, so the Python side can be compared byte for byte.
json describe(const fs::path& file) {
  const prt::ArchiveReader r = prt::ArchiveReader::open(file);
  json sections = json::array();
  for (const prt::SectionInfo& s : r.sections())
    sections.push_back({{"name", s.name},
                        {"type", prt::element_type_name(s.type)},
                        {"count", s.count},
                        {"xxh3", prt::hash_bytes(payload(r, s)).hex()}});
  return {{"file", file.filename().string()}, {"kind", r.kind()},
          {"kind_version", r.kind_version()}, {"checksum", r.checksum().hex()},
          {"bytes", r.size_bytes()},          {"sections", sections}};
}

// Light with distinct, exactly representable channels per pixel (k mod 7, 13 and 5 steps).
std::vector<prt::Rgb> fixture_light(std::size_t n) {
  std::vector<prt::Rgb> light(n);
  for (std::size_t k = 0; k < n; ++k)
    light[k] =
        prt::Rgb(0.25f + 0.125f * static_cast<float>(k % 7),
                 1.0f + 0.5f * static_cast<float>(k % 13), 0.0625f * static_cast<float>(k % 5));
  return light;
}

json write_transfer(const prt::TransferResult& result, const fs::path& file) {
  prt::save_transfer(result).write(file);
  const prt::TransferMatrix& t = result.transfer;
  std::vector<float> values(t.nnz());
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = t.value(i);
  const std::vector<prt::Rgb> light = fixture_light(t.cols());
  json light_json = json::array(), product = json::array();
  for (const prt::Rgb& l : light) light_json.push_back({l[0], l[1], l[2]});
  for (const prt::Vec3d& y : prt::relight_exact_double(t, light))
    product.push_back({y[0], y[1], y[2]});
  json out = describe(file);
  out.update({{"vertices", t.vertex_count()},
              {"local_count", t.local_count()},
              {"pixel_count", t.cols()},
              {"supersampling", t.supersampling()},
              {"rows", t.rows()},
              {"nnz", t.nnz()},
              {"narrow_columns", t.narrow_columns()},
              {"sh_order", result.sh ? result.sh->order() : 0},
              {"values_float32_xxh3", prt::hash_bytes(std::as_bytes(std::span(values))).hex()},
              {"light", light_json},
              {"product", product}});
  return out;
}

prt::TransferResult sphere_over_plane(int sh_order) {
  return prt::testing::sphere_over_plane_transfer(sh_order);
}

json write_element_types(const fs::path& file) {
  using L8 = std::numeric_limits<std::int8_t>;
  using L16 = std::numeric_limits<std::int16_t>;
  using L32 = std::numeric_limits<std::int32_t>;
  using L64 = std::numeric_limits<std::int64_t>;
  using F = std::numeric_limits<float>;
  using D = std::numeric_limits<double>;
  prt::ArchiveWriter w("element-types", 3);
  w.add_meta("note", "every element type at its extremes");
  w.add_section("u8", std::vector<std::uint8_t>{0, 1, 127, 128, 255});
  w.add_section("i8", std::vector<std::int8_t>{L8::min(), -1, 0, 1, L8::max()});
  w.add_section("u16", std::vector<std::uint16_t>{0, 1, 0x8000, 0xffff});
  w.add_section("i16", std::vector<std::int16_t>{L16::min(), -1, 0, L16::max()});
  w.add_section("u32", std::vector<std::uint32_t>{0, 1, 0x80000000u, 0xffffffffu});
  w.add_section("i32", std::vector<std::int32_t>{L32::min(), -1, 0, L32::max()});
  w.add_section("u64", std::vector<std::uint64_t>{0, 1, 0x8000000000000000ull, ~0ull});
  w.add_section("i64", std::vector<std::int64_t>{L64::min(), -1, 0, L64::max()});
  // -0, a quiet NaN with payload 1, infinities and the smallest denormal keep their bits.
  w.add_section("f32", std::vector<float>{-0.0f, std::bit_cast<float>(0x7fc00001u), F::infinity(),
                                          -F::infinity(), F::denorm_min(), F::max(), 0.1f});
  w.add_section(
      "f64", std::vector<double>{-0.0, std::bit_cast<double>(0x7ff8000000000001ull), D::infinity(),
                                 -D::infinity(), D::denorm_min(), D::max(), 0.1});
  w.add_section("empty", std::vector<double>{});
  w.write(file);
  return describe(file);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: prtlab-python-fixtures <output folder>\n";
    return 2;
  }
  try {
    prt::Progress::set_quiet(true);
    const fs::path dir = argv[1];
    fs::create_directories(dir);
    json expected;
    expected["transfers"] = json::array();

    // Order 5: what the SH-input backends (cpca_sh) ask for, so every backend is written below.
    prt::TransferResult with_sh = sphere_over_plane(5);
    expected["transfers"].push_back(write_transfer(with_sh, dir / "transfer_sh.prt"));
    // Wider than u16 columns: N = 6 * 128^2 = 98,304.
    prt::TransferResult wide;
    wide.transfer = prt::random_transfer(53, prt::RandomTransferSpec{3, 2, 128, 2, 0.003, {}});
    expected["transfers"].push_back(write_transfer(wide, dir / "transfer_wide.prt"));
    // An empty matrix: rows without any entry.
    prt::TransferResult empty;
    empty.transfer = prt::random_transfer(71, prt::RandomTransferSpec{5, 2, 2, 2, 0.0, {}});
    expected["transfers"].push_back(write_transfer(empty, dir / "transfer_empty.prt"));

    expected["compressed"] = json::array();
    const prt::TransferMatrix& t = with_sh.transfer;
    const prt::CubemapLayout cubemap(8);
    const prt::HemisphereGrid grid(4);
    auto& registry = prt::CompressorRegistry::instance();
    for (const std::string& name : registry.names()) {
      const bool wants_sh = registry.get(name).inputs.sh_order > 0;
      const prt::TransferInput input{t, wants_sh ? &*with_sh.sh : nullptr, cubemap, grid};
      const auto ct = registry.create(name, {})->compress(input, prt::Progress::null());
      const fs::path file = dir / fmt::format("compressed_{}.prt", name);
      prt::save_compressed(*ct, file);
      json c = describe(file);
      c.update({{"backend", name},
                {"flops_per_relight", ct->flops_per_relight()},
                {"storage_bytes", ct->storage().total_bytes()}});
      expected["compressed"].push_back(c);
    }

    expected["element_types"] = write_element_types(dir / "element_types.prt");

    std::ofstream(dir / "expected.json") << expected.dump(1) << '\n';
    std::cout << fmt::format(
        "wrote {} transfers, {} compressed transfers and the element types "
        "to {}\n",
        expected["transfers"].size(), expected["compressed"].size(), dir.string());
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "prtlab-python-fixtures: " << e.what() << '\n';
    return 1;
  }
}
