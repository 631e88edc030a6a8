#include "prtlab/compress/material_registry.h"

#include <fmt/format.h>

#include <map>

#include "compress/registry_entry_check.h"
#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"

namespace prt {
namespace {

constexpr std::string_view kMaterialKind = "compressed-material";
constexpr std::uint32_t kMaterialKindVersion = 1;

std::string known_names(const MaterialRegistry& r) {
  std::string out;
  for (const auto& n : r.names()) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "(none)" : out;
}

nlohmann::json basis_json(const MaterialLightBasis& b) {
  return {{"basis", std::string(to_string(b.basis))}, {"dim", b.dim}};
}

}  // namespace

MaterialRegistry& MaterialRegistry::instance() {
  static MaterialRegistry registry;
  return registry;
}

void MaterialRegistry::add(MaterialEntry entry) {
  if (entry.name.empty()) throw Error("material registry: an entry has no name");
  if (!entry.create || !entry.load)
    throw Error(fmt::format("material registry: '{}' lacks a create or load function", entry.name));
  if (entries_.contains(entry.name))
    throw Error(fmt::format("material registry: '{}' is registered twice ({} and {})", entry.name,
                            entries_.at(entry.name).origin, entry.origin));
  check_entry_params("material", entry.name, entry.params, entry.device_params);
  auto name = entry.name;
  entries_.emplace(std::move(name), std::move(entry));
}

const MaterialEntry& MaterialRegistry::get(const std::string& name) const {
  auto it = entries_.find(name);
  if (it == entries_.end())
    throw ParameterError(
        fmt::format("unknown material '{}' (registered: {})", name, known_names(*this)));
  return it->second;
}

std::vector<std::string> MaterialRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : entries_) out.push_back(k);
  return out;
}

std::unique_ptr<MaterialCompressor> MaterialRegistry::create(
    const std::string& name, const std::map<std::string, std::string>& params) const {
  const auto& e = get(name);
  return e.create(ParamSet(name, e.params, params));
}

ParamSet MaterialRegistry::device_options(const std::string& name,
                                          const std::map<std::string, std::string>& options) const {
  const auto& e = get(name);
  return ParamSet(name + " (device options)", e.device_params, options, ParamSet::Shared::kExclude);
}

namespace detail {

void register_material_static(MaterialEntry (*make)(), int api) noexcept {
  register_static(
      {.api = api,
       .kind = "material",
       .add =
           [make](const std::string& origin) {
             MaterialEntry e = make();
             e.origin = origin;
             std::string name = e.name;
             MaterialRegistry::instance().add(std::move(e));
             return name;
           },
       .remove = [](const std::string& name) { MaterialRegistry::instance().remove(name); }});
}

}  // namespace detail

std::shared_ptr<const CompressedMaterial> compress_material(
    const std::string& name, const std::map<std::string, std::string>& params,
    std::shared_ptr<const Btf> btf, Progress& progress) {
  if (!btf) throw ParameterError(fmt::format("material '{}': no BTF given", name));
  auto compressor = MaterialRegistry::instance().create(name, params);
  std::shared_ptr<const CompressedMaterial> out = compressor->compress({std::move(btf)}, progress);
  PRT_CHECK(out != nullptr, "material '{}' returned no compressed material", name);
  PRT_CHECK(out->backend() == name, "material '{}' produced a material of backend '{}'", name,
            out->backend());
  return out;
}

std::vector<std::shared_ptr<const CompressedMaterial>> compress_part_materials(
    std::span<const std::shared_ptr<const Btf>> part_btfs, const std::string& name,
    const std::map<std::string, std::string>& params) {
  std::map<const Btf*, std::shared_ptr<const CompressedMaterial>> done;
  std::vector<std::shared_ptr<const CompressedMaterial>> out;
  for (std::size_t p = 0; p < part_btfs.size(); ++p) {
    const auto& btf = part_btfs[p];
    if (!btf) throw ParameterError(fmt::format("material '{}': part {} has no BTF", name, p));
    auto& m = done[btf.get()];
    if (!m) m = compress_material(name, params, btf);
    out.push_back(m);
  }
  return out;
}

std::unique_ptr<DeviceMaterial> upload_materials(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const std::map<std::string, std::string>& device_options) {
  if (parts.empty() || !parts.front()) throw ParameterError("material upload: no materials given");
  const CompressedMaterial& first = *parts.front();
  for (std::size_t p = 0; p < parts.size(); ++p) {
    if (!parts[p]) throw ParameterError(fmt::format("material upload: part {} has none", p));
    if (parts[p]->backend() != first.backend())
      throw ParameterError(fmt::format(
          "material upload: part {} uses material '{}', part 0 '{}': one shading program "
          "evaluates one material backend",
          p, parts[p]->backend(), first.backend()));
    if (parts[p]->light_basis() != first.light_basis())
      throw ParameterError(fmt::format("material upload: part {} takes light in {}, part 0 in {}",
                                       p, parts[p]->light_basis().describe(),
                                       first.light_basis().describe()));
  }
  const ParamSet options =
      MaterialRegistry::instance().device_options(first.backend(), device_options);
  auto device = first.upload(context, parts, options);
  if (!device)
    throw ParameterError(fmt::format("material '{}' has no OpenCL side", first.backend()));
  return device;
}

void save_material(const CompressedMaterial& material, const std::filesystem::path& file) {
  ArchiveWriter w(std::string(kMaterialKind), kMaterialKindVersion);
  w.add_meta("backend", material.backend());
  w.add_meta("flops_per_pixel", material.flops_per_pixel());
  w.add_meta("storage_bytes", material.storage().total_bytes());
  w.add_meta("light_basis", basis_json(material.light_basis()));
  material.save(w);
  w.write(file);
}

std::unique_ptr<CompressedMaterial> load_material(const std::filesystem::path& file) {
  const ArchiveReader r = ArchiveReader::open(file, kMaterialKind, kMaterialKindVersion);
  const auto backend = r.meta_value<std::string>("backend");
  auto& registry = MaterialRegistry::instance();
  if (!registry.contains(backend))
    throw InputError(file,
                     fmt::format("compressed with material '{}', which is not registered here "
                                 "(registered: {}; a plugin material needs --plugin)",
                                 backend, known_names(registry)));
  auto out = registry.get(backend).load(r);
  if (!out) throw InputError(file, fmt::format("material '{}' loaded nothing", backend));
  return out;
}

}  // namespace prt
