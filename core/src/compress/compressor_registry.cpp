#include "prtlab/compress/compressor_registry.h"

#include <numeric>

#include "compress/registry_entry_check.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/compress/brdf_signal.h"
#include "prtlab/storage/archive.h"

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
  // A declared input that brings its parameters (brdf_signal.h): every backend on it reads the
  // same keys.
  if (entry.inputs.brdf_signal) {
    const auto specs = brdf_signal_param_specs();
    entry.params.insert(entry.params.end(), specs.begin(), specs.end());
  }
  // Fail at registration, not at first use, when a backend's own specs are inconsistent.
  check_entry_params("compressor", entry.name, entry.params, entry.device_params,
                     entry.light_params);
  if (entry.size_knob)
    entry.size_knob = resolve_size_knob(entry.name, *entry.size_knob, entry.params);
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

ParamSet CompressorRegistry::device_options(
    const std::string& name, const std::map<std::string, std::string>& options) const {
  const auto& e = get(name);
  return ParamSet(name + " (device options)", e.device_params, options, ParamSet::Shared::kExclude);
}

ParamSet CompressorRegistry::light_options(
    const std::string& name, const std::map<std::string, std::string>& options) const {
  const auto& e = get(name);
  return ParamSet(name + " (light options)", e.light_params, options, ParamSet::Shared::kExclude);
}

std::unique_ptr<DeviceRelighter> upload_compressed(
    const CompressedTransfer& ct, ClContext& context,
    const std::map<std::string, std::string>& device_options) {
  const auto& registry = CompressorRegistry::instance();
  return ct.upload(context, registry.device_options(ct.backend(), device_options));
}

namespace detail {

void register_compressor_static(CompressorEntry (*make)(), int api) noexcept {
  register_static(
      {.api = api,
       .kind = "compressor",
       .add =
           [make](const std::string& origin) {
             CompressorEntry e = make();
             e.origin = origin;
             std::string name = e.name;
             CompressorRegistry::instance().add(std::move(e));
             return name;
           },
       .remove = [](const std::string& name) { CompressorRegistry::instance().remove(name); }});
}

}  // namespace detail

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
