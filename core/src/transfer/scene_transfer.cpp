#include "prtlab/transfer/scene_transfer.h"

#include <toml++/toml.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <sstream>

#include "prtlab/base/error.h"
#include "prtlab/base/statistics.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/transfer_io.h"

namespace prt {
namespace {

std::vector<char> read_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open for reading");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Camera presets do not change T, so a view-only edit of the scene file must not invalidate the
// transfer cache: hash the parsed file with its [[view]] tables removed. The re-serialised TOML
// is canonical for the same content (toml++ prints keys in sorted order).
std::string scene_text_without_views(const std::filesystem::path& file) {
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(file, std::string("TOML parse error: ") + std::string(e.description()));
  }
  root.erase("view");
  std::ostringstream os;
  os << root;
  return os.str();
}

}  // namespace

Hash128 scene_input_hash(const SceneDesc& desc) {
  Hasher h;
  h.add("prtlab-scene-inputs").add(kMeshPipelineVersion);
  const std::string scene_text = scene_text_without_views(desc.file);
  h.add_array(std::span<const char>(scene_text.data(), scene_text.size()));
  for (const auto& part : desc.parts) {
    if (part.mesh.starts_with("procedural:")) continue;
    const auto bytes = read_bytes(resolve_mesh(part.mesh, desc.file));
    h.add(part.mesh).add_array(std::span<const char>(bytes));
  }
  return h.digest();
}

SceneTransfer precompute_scene_transfer(const SceneDesc& desc, const PrecomputeOptions& options,
                                        StageCache& cache) {
  const auto t0 = std::chrono::steady_clock::now();
  Hasher h;
  h.add(kTransferArchiveKind)
      .add(kTransferArchiveVersion)
      .add(scene_input_hash(desc))
      .add(options.sh_order);
  SceneTransfer out;
  out.key = h.digest();
  out.cache_file = cache.path_for("transfer", out.key);
  const auto transfer_params = [&](const SceneDesc& d) {
    TransferParams p;
    p.cubemap_resolution = d.cubemap_resolution;
    p.local_grid = d.local_grid;
    p.supersampling = d.supersampling;
    p.sh_order = options.sh_order;
    p.show_progress = options.show_progress;
    return p;
  };
  if (options.comm && options.comm->distributed()) {
    Communicator& comm = *options.comm;
    // One decision for every rank: the root's look at the cache.
    const bool hit =
        comm.broadcast(
            {static_cast<std::uint8_t>(comm.is_root() && options.cache == CacheMode::kUse &&
                                       cache.contains("transfer", out.key))})[0] != 0;
    out.holds_result = comm.is_root();
    if (hit) {
      if (comm.is_root())
        // A cached file found corrupt on loading is recomputed here, by the root alone.
        out.result = cache.get_or_compute(
            "transfer", out.key,
            [&] {
              return save_transfer(compute_transfer(build_scene(desc).mesh, transfer_params(desc)));
            },
            [](const ArchiveReader& r) { return load_transfer(r); }, CacheMode::kUse);
      out.cache_hit = true;
      out.seconds = seconds_since(t0);
      return out;
    }
    const auto tm = std::chrono::steady_clock::now();
    const Scene scene = build_scene(desc);
    out.mesh_seconds = seconds_since(tm);
    DistributedTransfer d = compute_transfer_distributed(scene.mesh, transfer_params(desc), comm);
    if (comm.is_root()) {
      cache.fetch(
          "transfer", out.key, [&] { return save_transfer(d.result); }, [](const ArchiveReader&) {},
          options.cache == CacheMode::kOff ? CacheMode::kOff : CacheMode::kRefresh);
      out.result = std::move(d.result);
      out.shares = std::move(d.shares);
    }
    out.seconds = seconds_since(t0);
    return out;
  }
  bool computed = false;
  out.result = cache.get_or_compute(
      "transfer", out.key,
      [&] {
        computed = true;
        const auto tm = std::chrono::steady_clock::now();
        const Scene scene = build_scene(desc);
        out.mesh_seconds = seconds_since(tm);
        return save_transfer(compute_transfer(scene.mesh, transfer_params(desc)));
      },
      [](const ArchiveReader& r) { return load_transfer(r); }, options.cache);
  out.cache_hit = !computed;
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace prt
