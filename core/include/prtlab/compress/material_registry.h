#pragma once
// Registry of material backends, filled by one line per backend, as for transfer compressors:
//
//   PRT_REGISTER_MATERIAL(my_material_entry);   // compressors/<name>/<name>.cpp, or a plugin
//
// where my_material_entry() returns a MaterialEntry. A plugin registers materials with the same
// line when load_plugin() opens it (plugin.h). Material and transfer backends are separate
// kinds with separate registries; a backend folder under compressors/ registers one of the two
// under its folder's name (tests/core/registry_test.cpp).
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "prtlab/compress/material_compressor.h"
#include "prtlab/compress/params.h"
#include "prtlab/compress/plugin.h"

namespace prt {

class ArchiveReader;

struct MaterialEntry {
  std::string name;
  std::string description;        ///< one line: the method and its paper
  std::vector<ParamSpec> params;  ///< backend-specific; shared ones are added by ParamSet
  /// Options of the OpenCL path only: they may change float rounding, never the result
  /// otherwise; passed to upload(), never to create(), and never saved.
  std::vector<ParamSpec> device_params;
  /// At default parameters the reflectance equals the full BTF up to float rounding.
  bool lossless = false;
  std::function<std::unique_ptr<MaterialCompressor>(const ParamSet&)> create;
  std::function<std::unique_ptr<CompressedMaterial>(const ArchiveReader&)> load;
  std::string origin = "built-in";  ///< "built-in" or the plugin's path
  /// Bumped whenever the compressed output for the same input and parameters changes.
  std::uint32_t version = 1;
};

class MaterialRegistry {
 public:
  static MaterialRegistry& instance();

  /// Throws when the name is taken or the entry is incomplete or inconsistent.
  void add(MaterialEntry entry);
  bool contains(const std::string& name) const { return entries_.contains(name); }
  const MaterialEntry& get(const std::string& name) const;  ///< ParameterError listing names
  std::vector<std::string> names() const;
  /// Removes an entry (a plugin that failed to load); unknown names are ignored.
  void remove(const std::string& name) { entries_.erase(name); }

  /// Validate parameters and construct.
  std::unique_ptr<MaterialCompressor> create(
      const std::string& name, const std::map<std::string, std::string>& params) const;
  /// Validate device options against the backend's device_params.
  ParamSet device_options(const std::string& name,
                          const std::map<std::string, std::string>& options) const;

 private:
  std::map<std::string, MaterialEntry> entries_;
};

namespace detail {
/// Registers make()'s entry through register_static() (plugin.h); `api` is checked first.
void register_material_static(MaterialEntry (*make)(), int api) noexcept;
}  // namespace detail

/// Static registrar used by PRT_REGISTER_MATERIAL (inline: `api` is the registering code's).
struct MaterialRegistrar {
  explicit MaterialRegistrar(MaterialEntry (*make)(), int api = kPluginApiVersion) noexcept {
    detail::register_material_static(make, api);
  }
};

/// Compresses one BTF with the material backend `name` (parameters validated).
std::shared_ptr<const CompressedMaterial> compress_material(
    const std::string& name, const std::map<std::string, std::string>& params,
    std::shared_ptr<const Btf> btf, Progress& progress = Progress::null());

/// The material of every part (part order) from the parts' BTFs: each distinct BTF is
/// compressed once and its material shared by the parts that share the BTF.
std::vector<std::shared_ptr<const CompressedMaterial>> compress_part_materials(
    std::span<const std::shared_ptr<const Btf>> part_btfs, const std::string& name,
    const std::map<std::string, std::string>& params);

/// The device side of the parts' materials. ParameterError when a part has none, when they are
/// of different backends or light bases (one shading program evaluates one backend), or for a
/// bad device option; then the first part's upload() with the validated options.
std::unique_ptr<DeviceMaterial> upload_materials(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const std::map<std::string, std::string>& device_options = {});

/// Save a compressed material with a header naming its backend (kind "compressed-material",
/// metadata backend, flops_per_pixel, storage_bytes, light_basis); load dispatches on it.
void save_material(const CompressedMaterial& material, const std::filesystem::path& file);
std::unique_ptr<CompressedMaterial> load_material(const std::filesystem::path& file);

}  // namespace prt

#define PRT_REGISTER_MATERIAL(make_entry)                                               \
  static const ::prt::MaterialRegistrar PRT_CONCAT(prt_material_registrar_, __LINE__) { \
    &make_entry                                                                         \
  }
