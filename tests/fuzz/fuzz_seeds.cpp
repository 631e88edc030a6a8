// Writes the seed corpora of the fuzz targets (docs/fuzzing.md) from prtlab's own writers, so
// the seeds follow the formats as they change: <output>/<target>/<name> for every target of
// tests/fuzz/CMakeLists.txt. Small on purpose: libFuzzer derives its input size limit from the
// largest seed, and small inputs run fast.
//
//   mesh           a selector byte (fuzz_mesh.cpp's mode) + OFF / OBJ / PLY / STL text
//   environment    EXRs: prtlab's float writer and OpenEXR's half, RGBA, luminance, tiled, RLE
//   scene          the scene files of scenes/ and one using every key
//   archive        a transfer matrix with SH, one without, every element type, a compressed
//   transfer_load  one compressed transfer per registered backend (default parameters)
//   material_load  one compressed material per registered material backend
//   experiment     the experiment files of the repository and the refusals of docs/robustness.md
//                  (a grid past the point budget, a backend twice, a type error on a variant)
//   ubo            FMF and BDI files from prtlab's writers and headers declaring 65536^2 texels
//
// Usage: prtlab-fuzz-seeds <output folder>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfTiledOutputFile.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "experiment_spec.h"
#include "prtlab/base/log.h"
#include "prtlab/base/progress.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/btf/ubo_btf.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/image/image_io.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_io.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/sphere_over_plane.h"

namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& file, std::string_view text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  if (!out) throw std::runtime_error(file.string() + ": cannot be written");
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot be read");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ---- mesh: the selector byte is the index into fuzz_mesh.cpp's kModes ----------------------

enum MeshMode : char {
  kOff = 0,
  kObj = 1,
  kPly = 2,
  kStl = 3,
  kObjByMaterial = 4,
  kObjByObject = 5,
  kPlyByObject = 6
};

void mesh_seed(const fs::path& dir, const std::string& name, MeshMode mode, std::string_view text) {
  std::string bytes(1, static_cast<char>(mode));
  bytes.append(text);
  write_text(dir / name, bytes);
}

void write_mesh_seeds(const fs::path& dir) {
  constexpr std::string_view kCube =
      "OFF\n8 6 12\n-1 -1 -1\n1 -1 -1\n1 1 -1\n-1 1 -1\n-1 -1 1\n1 -1 1\n1 1 1\n-1 1 1\n"
      "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n";
  mesh_seed(dir, "cube.off", kOff, kCube);
  // Keyword variants: colours (C), normals (N), texture coordinates (ST), homogeneous (4),
  // comments, counts on the keyword line, a degenerate face and faces of one and two vertices.
  mesh_seed(dir, "variants.off", kOff,
            "# comment\nSTCNOFF 4 4 0\n0 0 0 0 0 1 0.1 0.2 0.3 1 0 0\n1 0 0 0 0 1 0.1 0.2 0.3 1 "
            "1 0\n0 1 0 0 0 1 0.1 0.2 0.3 1 0 1\n1 1 0 0 0 1 1 1 1 1 1 1\n3 0 1 2\n3 1 3 2\n"
            "2 0 1\n1 3\n");
  mesh_seed(dir, "homogeneous.off", kOff, "4OFF\n3 1 0\n0 0 0 1\n2 0 0 2\n0 4 0 4\n3 0 1 2\n");
  const prt::Mesh sphere = prt::make_sphere(0.5, 6, 3);
  const fs::path obj = dir / "sphere.obj.tmp";
  prt::save_mesh_obj(sphere, obj);
  const std::string sphere_obj = read_text(obj);
  fs::remove(obj);
  mesh_seed(dir, "sphere.obj", kObj, sphere_obj);
  constexpr std::string_view kGroups =
      "mtllib none.mtl\no box\ng side\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nusemtl wood\nf 1/1/1 2/2/1 3/3/1\nf -4/1 -2/3 -1/2\n"
      "o lid\nusemtl metal\nf 1//1 2//1 \\\n 5//1\nl 1 2\np 3\n";
  mesh_seed(dir, "groups.obj", kObj, kGroups);
  mesh_seed(dir, "groups_by_material.obj", kObjByMaterial, kGroups);
  mesh_seed(dir, "groups_by_object.obj", kObjByObject, kGroups);
  constexpr std::string_view kPlyText =
      "ply\nformat ascii 1.0\ncomment prtlab fuzz seed\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nproperty float s\nproperty float t\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n"
      "1 1 0 1 1\n0 1 0 0 1\n3 0 1 2\n4 0 2 3 1\n";
  mesh_seed(dir, "quad.ply", kPly, kPlyText);
  mesh_seed(dir, "quad_by_object.ply", kPlyByObject, kPlyText);
  // Binary PLY: the same quad, little-endian.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float xyz[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  binary.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
  const std::int32_t face[4] = {0, 1, 2, 3};
  binary.push_back(4);
  binary.append(reinterpret_cast<const char*>(face), sizeof(face));
  mesh_seed(dir, "quad_binary.ply", kPly, binary);
  mesh_seed(dir, "triangle.stl", kStl,
            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
            "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n"
            "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
}

// ---- environment -----------------------------------------------------------------------------

void write_environment_seeds(const fs::path& dir) {
  const prt::LatLongImage sky = prt::SunSky{}.to_latlong(16, 8, 1);
  prt::RgbImage image(sky.width, sky.height);
  image.pixels = sky.texels;
  prt::write_exr(image, dir / "sunsky_float_zip.exr");

  std::vector<Imf::Rgba> half(static_cast<std::size_t>(sky.width) * sky.height);
  for (std::size_t i = 0; i < half.size(); ++i)
    half[i] = Imf::Rgba(sky.texels[i][0], sky.texels[i][1], sky.texels[i][2], 1.f);
  const auto write_rgba = [&](const fs::path& file, Imf::RgbaChannels channels,
                              Imf::Compression compression) {
    Imf::RgbaOutputFile out(file.c_str(), sky.width, sky.height, channels, 1.f, Imath::V2f(0, 0),
                            1.f, Imf::INCREASING_Y, compression);
    out.setFrameBuffer(half.data(), 1, static_cast<std::size_t>(sky.width));
    out.writePixels(sky.height);
  };
  write_rgba(dir / "sunsky_half_rgba_none.exr", Imf::WRITE_RGBA, Imf::NO_COMPRESSION);
  write_rgba(dir / "sunsky_half_rgb_rle.exr", Imf::WRITE_RGB, Imf::RLE_COMPRESSION);
  write_rgba(dir / "sunsky_half_y_piz.exr", Imf::WRITE_Y, Imf::PIZ_COMPRESSION);

  // Tiled, float luminance: another file layout and channel set the loader accepts.
  Imf::Header header(sky.width, sky.height);
  header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  header.setTileDescription(Imf::TileDescription(8, 4, Imf::ONE_LEVEL));
  header.compression() = Imf::NO_COMPRESSION;
  std::vector<float> y(half.size());
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = sky.texels[i][1];
  Imf::TiledOutputFile tiled((dir / "sunsky_tiled_y.exr").c_str(), header);
  Imf::FrameBuffer fb;
  fb.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(y.data()), sizeof(float),
                            sizeof(float) * static_cast<std::size_t>(sky.width)));
  tiled.setFrameBuffer(fb);
  tiled.writeTiles(0, tiled.numXTiles() - 1, 0, tiled.numYTiles() - 1);
}

// ---- scene -----------------------------------------------------------------------------------

void write_scene_seeds(const fs::path& dir, const fs::path& source_dir) {
  for (const auto& entry : fs::directory_iterator(source_dir / "scenes"))
    if (entry.path().extension() == ".toml")
      fs::copy_file(entry.path(), dir / entry.path().filename(),
                    fs::copy_options::overwrite_existing);
  write_text(
      dir / "every_key.toml",
      "name = \"every-key\"\ndescription = \"all keys\"\nlocal_grid = 4\n"
      "cubemap_resolution = 8\nsupersampling = 1\n"
      "[[part]]\nname = \"a\"\nmesh = \"model.obj\"\nbtf = \"stucco\"\nuv_scale = [2.0, 3.0]\n"
      "uv_mapping = \"mesh\"\ntarget_vertices = 200\nsubdivision = \"linear\"\n"
      "groups = [\"Seat*\", \"Ba?k\"]\ngroup_by = \"object\"\nnormalize = true\n"
      "transform = { scale = [1, 2, 1], rotate_deg = [0, 90, 0], translate = [0, 1, 0] }\n"
      "[[part.instance]]\ntranslate = [1, 0, 0]\nscale = [1, 2, 1]\n"
      "[[part]]\nmesh = \"procedural:torus\"\nuv_mapping = \"planar\"\nuv_scale = 4.0\n"
      "[part.params]\nmajor_radius = 0.5\nminor_radius = 0.2\n"
      "[[view]]\nname = \"framed\"\nfrom = [0, 0.3, 1]\nfov = 30\nfill = 0.8\n"
      "[[view]]\nname = \"explicit\"\neye = [0.5, 0.6, 1.2]\ntarget = [0, 0.4, 0]\n"
      "up = [0, 1, 0]\n");
}

// ---- archives --------------------------------------------------------------------------------

// A tiny scene: every backend, the SH ones included, compresses it at default parameters (the
// Python reader's fixtures use a larger one of the same shape).
prt::TransferResult tiny_transfer(int sh_order) {
  return prt::testing::sphere_over_plane_transfer(sh_order, 3, 8);
}

// The backend's size knob at its smallest-storage end: small seeds (libFuzzer's input size
// limit follows the largest) that compress fast. Defaults where the backend has no knob.
std::map<std::string, std::string> smallest_params(const prt::CompressorEntry& entry) {
  if (!entry.size_knob || !entry.size_knob->min || !entry.size_knob->max) return {};
  const prt::SizeKnob& knob = *entry.size_knob;
  const double value =
      knob.direction == prt::SizeKnob::Direction::kLargerIsMoreStorage ? *knob.min : *knob.max;
  const auto spec = std::find_if(entry.params.begin(), entry.params.end(),
                                 [&](const prt::ParamSpec& p) { return p.key == knob.key; });
  const bool integer = spec != entry.params.end() && spec->type == prt::ParamType::kInt;
  return {{knob.key,
           integer ? fmt::format("{}", static_cast<long long>(value)) : fmt::format("{}", value)}};
}

void write_archive_seeds(const fs::path& archive_dir, const fs::path& transfer_dir) {
  // Order 2 keeps the SH section small; the backends get the order they declare.
  prt::save_transfer(tiny_transfer(2)).write(archive_dir / "transfer_sh.prt");
  const prt::TransferResult with_sh = tiny_transfer(5);
  prt::TransferResult plain;
  plain.transfer = with_sh.transfer;
  prt::save_transfer(plain).write(archive_dir / "transfer.prt");

  prt::ArchiveWriter types("element-types", 1);
  types.add_meta("note", "one section of every element type");
  types.add_section("u8", std::vector<std::uint8_t>{0, 255});
  types.add_section("i8", std::vector<std::int8_t>{-128, 127});
  types.add_section("u16", std::vector<std::uint16_t>{0, 65535});
  types.add_section("i16", std::vector<std::int16_t>{-32768, 32767});
  types.add_section("u32", std::vector<std::uint32_t>{0, 4294967295u});
  types.add_section("i32", std::vector<std::int32_t>{-1, 1});
  types.add_section("u64", std::vector<std::uint64_t>{0, 1});
  types.add_section("i64", std::vector<std::int64_t>{-1, 1});
  types.add_section("f32", std::vector<float>{-0.f, 1.f});
  types.add_section("f64", std::vector<double>{0.5, 2.0});
  types.add_section("empty", std::vector<double>{});
  types.write(archive_dir / "element_types.prt");

  const prt::CubemapLayout cubemap(8);
  const prt::HemisphereGrid grid(4);
  auto& registry = prt::CompressorRegistry::instance();
  for (const std::string& name : registry.names()) {
    const bool wants_sh = registry.get(name).inputs.sh_order > 0;
    const prt::TransferInput input{with_sh.transfer, wants_sh ? &*with_sh.sh : nullptr, cubemap,
                                   grid};
    std::unique_ptr<prt::CompressedTransfer> ct;
    try {
      ct = registry.create(name, smallest_params(registry.get(name)))
               ->compress(input, prt::Progress::null());
    } catch (const std::exception&) {
      // Some knobs' extremes do not fit so small a matrix: the defaults always do.
      ct = registry.create(name, {})->compress(input, prt::Progress::null());
    }
    prt::save_compressed(*ct, transfer_dir / fmt::format("{}.prt", name));
  }
  fs::copy_file(transfer_dir / "uncompressed.prt", archive_dir / "compressed_uncompressed.prt",
                fs::copy_options::overwrite_existing);
}

// A 4 x 4-texel checker BTF on side x side view and light grids: small seeds, fast to read.
prt::Btf seed_btf(int side) {
  prt::BtfParams p;
  p.resolution = 4;
  p.view_side = side;
  p.light_side = side;
  p.supersampling = 1;
  p.geometry_grid = 32;
  return prt::generate_btf(prt::make_btf_material("checker", 32), p);
}

void write_material_seeds(const fs::path& dir) {
  const auto btf = std::make_shared<const prt::Btf>(seed_btf(3));
  for (const std::string& name : prt::MaterialRegistry::instance().names())
    prt::save_material(*prt::compress_material(name, {}, btf), dir / fmt::format("{}.prt", name));
}

// ---- experiment files --------------------------------------------------------------------------

void write_experiment_seeds(const fs::path& dir) {
  int n = 0;
  for (const fs::path& f : prt::experiments::experiment_files())
    fs::copy_file(f, dir / fmt::format("{:02d}-{}", n++, f.filename().string()),
                  fs::copy_options::overwrite_existing);
  const std::string head =
      "name = \"seed\"\nkind = \"sweep\"\nscenes = [\"tiny-sphere-plane\"]\n"
      "environments = [\"sun:3e4\"]\n";
  std::string wide;
  for (int v = 1; v <= 50; ++v) wide += fmt::format("{}{}", v == 1 ? "" : ", ", v);
  write_text(dir / "grid-past-budget.toml",
             head + fmt::format("backends = [\"cpca\"]\n[grid.cpca]\nclusters = [{0}]\n"
                                "vectors = [{0}]\n",
                                wide));
  write_text(dir / "backend-twice.toml", head + "backends = [\"cpca\", \"haar\", \"cpca\"]\n");
  write_text(dir / "star-and-name.toml", head + "backends = [\"*\", \"cpca\"]\n");
  write_text(dir / "points-and-grid.toml",
             head +
                 "backends = [\"cpca\"]\n[grid.cpca]\nclusters = [4]\n"
                 "[[points.cpca]]\nclusters = 8\n");
  write_text(dir / "variant-type-error.toml",
             head + "backends = [\"cpca\"]\n[variant.quick]\nrepeats = \"three\"\n");
  write_text(dir / "unknown-kind.toml",
             "name = \"seed\"\nkind = \"tabel\"\nscenes = [\"tiny-sphere-plane\"]\n");
}

// ---- UBO measured BTFs
// ---------------------------------------------------------------------------

// A "!FMF06FC" / "!BDIF06R2!" header (ubo_btf.h) with one view and one light at the zenith,
// declaring side x side texels and holding nothing after it.
std::string ubo_header(std::string_view signature, std::uint32_t side) {
  std::string b(signature);
  const auto u32 = [&](std::uint32_t v) {
    for (int k = 0; k < 4; ++k) b.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
  };
  const auto f32 = [&](float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    u32(u);
  };
  u32(4 + 4 + 240 + 4 + 12);  // meta data block: its size, version, 240 bytes, 4 floats
  u32(1);
  b.append(240, '\0');
  f32(10.f);
  for (int c = 0; c < 3; ++c) f32(1.f);
  u32(1);  // one view at (0, 0) with one light at (0, 0)
  f32(0.f);
  f32(0.f);
  u32(1);
  f32(0.f);
  f32(0.f);
  u32(side);
  u32(side);
  return b;
}

void write_ubo_seeds(const fs::path& dir) {
  const prt::Btf btf = seed_btf(2);
  prt::write_ubo_fmf(btf, dir / "exact.btf");
  prt::write_ubo_fmf(btf, dir / "rank1-half.btf", {.components = 1, .scalar_bytes = 2});
  prt::write_ubo_bdi(btf, dir / "sparse.btf");
  for (const std::string_view signature : {"!FMF06FC", "!BDIF06R2!"})
    for (const std::uint32_t side : {65536u, 16384u})
      write_text(dir / fmt::format("{}-{}.btf", signature.substr(1, 3), side),
                 ubo_header(signature, side));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: prtlab-fuzz-seeds <output folder>\n";
    return 2;
  }
  try {
    prt::Progress::set_quiet(true);
    prt::set_log_level(prt::LogLevel::kWarn);
    const fs::path out = argv[1];
    const auto folder = [&](const char* target) {
      const fs::path dir = out / target;
      fs::remove_all(dir);
      fs::create_directories(dir);
      return dir;
    };
    write_mesh_seeds(folder("mesh"));
    write_environment_seeds(folder("environment"));
    write_scene_seeds(folder("scene"), PRTLAB_SOURCE_DIR);
    write_archive_seeds(folder("archive"), folder("transfer_load"));
    write_material_seeds(folder("material_load"));
    write_experiment_seeds(folder("experiment"));
    write_ubo_seeds(folder("ubo"));
  } catch (const std::exception& e) {
    std::cerr << "prtlab-fuzz-seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
