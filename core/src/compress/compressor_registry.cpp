#include "prtlab/compress/compressor_registry.h"

#include <dlfcn.h>

#include <numeric>

#include "prtlab/storage/archive.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"

namespace prt {
namespace {

constexpr std::string_view kCompressedKind = "compressed-transfer";
constexpr std::uint32_t kCompressedKindVersion = 1;

std::string known_names(const CompressorRegistry& r) {
  std::string out;
  for (const auto& n : r.names()) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "(none)" : out;
}

}  // namespace

std::uint64_t StorageReport::total_bytes() const {
  return std::accumulate(components.begin(), components.end(), std::uint64_t{0},
                         [](std::uint64_t s, const StorageComponent& c) { return s + c.bytes; });
}

CompressorRegistry& CompressorRegistry::instance() {
  static CompressorRegistry registry;
  return registry;
}

void CompressorRegistry::add(CompressorEntry entry) {
  if (entry.name.empty()) throw Error("compressor registry: an entry has no name");
  if (!entry.create || !entry.load)
    throw Error(
        fmt::format("compressor registry: '{}' lacks a create or load function", entry.name));
  if (entries_.contains(entry.name))
    throw Error(fmt::format("compressor registry: '{}' is registered twice ({} and {})", entry.name,
                            entries_.at(entry.name).origin, entry.origin));
  // Fail at registration, not at first use, when a backend's own specs are inconsistent.
  ParamSet validate(entry.name, entry.params, {});
  (void)validate;
  auto name = entry.name;
  entries_.emplace(std::move(name), std::move(entry));
}

const CompressorEntry& CompressorRegistry::get(const std::string& name) const {
  auto it = entries_.find(name);
  if (it == entries_.end())
    throw ParameterError(
        fmt::format("unknown backend '{}' (registered: {})", name, known_names(*this)));
  return it->second;
}

std::vector<std::string> CompressorRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : entries_) out.push_back(k);
  return out;
}

std::unique_ptr<Compressor> CompressorRegistry::create(
    const std::string& name, const std::map<std::string, std::string>& params) const {
  const auto& e = get(name);
  return e.create(ParamSet(name, e.params, params));
}

std::vector<std::string> load_plugin(const std::filesystem::path& library) {
  if (!std::filesystem::exists(library)) throw InputError(library, "plugin library not found");
  // RTLD_NODELETE: a plugin's registered lambdas must outlive any handle we might drop.
  void* handle = ::dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (!handle) throw InputError(library, fmt::format("cannot load plugin: {}", ::dlerror()));
  using VersionFn = int (*)();
  using RegisterFn = void (*)(CompressorRegistry&);
  auto version = reinterpret_cast<VersionFn>(::dlsym(handle, "prtlab_plugin_api_version"));
  auto reg = reinterpret_cast<RegisterFn>(::dlsym(handle, "prtlab_register_plugin"));
  if (!version || !reg)
    throw InputError(
        library,
        "not a prtlab plugin (it must export extern \"C\" prtlab_plugin_api_version() and "
        "prtlab_register_plugin(prt::CompressorRegistry&))");
  const int v = version();
  if (v != kPluginApiVersion)
    throw InputError(
        library,
        fmt::format("plugin API version {} does not match this prtlab's version {}; rebuild the "
                    "plugin against this prtlab",
                    v, kPluginApiVersion));
  auto& registry = CompressorRegistry::instance();
  const auto before = registry.names();
  // Entries registered by the plugin are tagged with its path (for `prtlab list`).
  CompressorRegistry staging;
  reg(staging);
  std::vector<std::string> added;
  for (const auto& name : staging.names()) {
    CompressorEntry e = staging.get(name);
    e.origin = library.string();
    registry.add(std::move(e));
    added.push_back(name);
  }
  if (added.empty()) log_warn("plugin {} registered no compressor", library.string());
  return added;
}

void save_compressed(const CompressedTransfer& ct, const std::filesystem::path& file) {
  ArchiveWriter w(std::string(kCompressedKind), kCompressedKindVersion);
  w.add_meta("backend", ct.backend());
  w.add_meta("flops_per_relight", ct.flops_per_relight());
  w.add_meta("storage_bytes", ct.storage().total_bytes());
  ct.save(w);
  w.write(file);
}

std::unique_ptr<CompressedTransfer> load_compressed(const std::filesystem::path& file) {
  const ArchiveReader r = ArchiveReader::open(file, kCompressedKind, kCompressedKindVersion);
  const auto backend = r.meta_value<std::string>("backend");
  auto& registry = CompressorRegistry::instance();
  if (!registry.contains(backend))
    throw InputError(
        file,
        fmt::format("compressed with backend '{}', which is not registered here (registered: {}; "
                    "a plugin backend needs --plugin)",
                    backend, known_names(registry)));
  return registry.get(backend).load(r);
}

}  // namespace prt
