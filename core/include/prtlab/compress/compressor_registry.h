#pragma once
// Registry of compressor backends, filled by one line per backend:
//
//   PRT_REGISTER_COMPRESSOR(my_backend_entry);   // at the bottom of compressors/<name>/<name>.cpp
//
// where my_backend_entry() returns a CompressorEntry. The same line registers a plugin's
// backend when load_plugin() opens the plugin (plugin.h). Built-in backends are CMake OBJECT
// libraries, so their static registrars survive linking; a test derives the expected list of
// backends from the folders and compares it with the registry.
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/params.h"
#include "prtlab/compress/plugin.h"
#include "prtlab/compress/size_knob.h"
#include "prtlab/transfer/local_radiance.h"

namespace prt {

/// What a backend needs besides the pixel-basis T, which every backend gets (it is what all
/// are measured against). prepare_scene() (backend_input.h) builds exactly the union of what
/// the backends of a run declare, so no caller names a backend to know what to compute.
struct BackendInputs {
  int sh_order = 0;   ///< the SH transfer of this order (n^2 x n^2 per vertex); 0: none
  bool mesh = false;  ///< the scene's mesh (parts, frames, UVs)
  bool btfs = false;  ///< the scene's BTFs, one per part
  /// The BRDF-weighted signal (brdf_signal.h): the entry gets its parameters at registration
  /// and TransferInput::brdf_signal, which folds T once per BRDF for every backend of a run.
  bool brdf_signal = false;
};

/// A number a paper publishes for a backend on one of its scenes at given parameters, printed
/// beside ours by `prtlab compress` when the scene and those parameters match (docs/cli.md).
struct PublishedNumber {
  std::string scene;                          ///< prtlab's scene name ("chair")
  std::map<std::string, std::string> params;  ///< the backend's parameters it was measured at
  std::string text;                           ///< "12 terms per row: 37.1 MB"
  std::string source;                         ///< "Sun et al. 2008, Fig. 6"
};

struct CompressorEntry {
  std::string name;
  std::string description;        ///< one line: the method and its paper
  std::vector<ParamSpec> params;  ///< backend-specific; shared ones are added by ParamSet
  /// Options of the OpenCL path only (kernel variant, lanes, id width): they may change float
  /// rounding, never the result otherwise. Passed to upload(), never to create(); not saved,
  /// not in the stage-cache key, so changing one never recompresses. The conformance suite
  /// checks every combination of their choices against the C++ relight.
  std::vector<ParamSpec> device_params;
  /// Options of the light projection at run time (Ng 2003's N light terms): unlike device
  /// options they change the relight's result, but never the compressed data, so they are not
  /// saved and not in a compression's cache key; changing one never recompresses. Passed to
  /// CompressedTransfer::project_light_under(radiance, options) through project_light_with()
  /// (light_options.h); an experiment point's parameters may hold them beside `params`.
  std::vector<ParamSpec> light_params;
  BackendInputs inputs;  ///< what compress() reads from TransferInput besides T
  /// The basis every compressed result of this backend relights into (output_basis()), known
  /// before compressing so that callers size and shade without a result in hand.
  RadianceBasis output_basis = RadianceBasis::kPixel;
  /// The parameter that trades storage against error; none for a fixed-size backend. The
  /// registry validates it against `params` and fills in its range (resolve_size_knob()).
  std::optional<SizeKnob> size_knob;
  /// Rough seconds one compression at default parameters takes on the 3,286-vertex bunny on
  /// one 2-core machine (the backend's README says where it was measured); the harness scales
  /// it by a scene's vertex count to estimate how long an experiment file will take before it
  /// runs. 0: the backend declares none (the estimate says so).
  double cost_hint_seconds = 0;
  bool lossless =
      false;  ///< at default parameters, relight equals the exact product up to float rounding
  /// compress() splits its own work over the ranks of a collective scope (distributed/
  /// communicator.h, CollectiveScope), with the one-process result. A distributed experiment then
  /// compresses this backend's points on every rank together before it hands out the points to
  /// measure, so that a slow point uses the whole allocation.
  bool collective = false;
  std::function<std::unique_ptr<Compressor>(const ParamSet&)> create;
  std::function<std::unique_ptr<CompressedTransfer>(const ArchiveReader&)> load;
  std::string origin = "built-in";  ///< "built-in" or the plugin's path
  /// Bump whenever the backend's compressed output for the same input and parameters changes
  /// (algorithm or file layout): it is part of the stage-cache key of compressed results.
  std::uint32_t version = 1;
  /// The papers' numbers for this backend (never part of any cache key).
  std::vector<PublishedNumber> published;
};

class CompressorRegistry {
 public:
  static CompressorRegistry& instance();

  /// Throws when the name is taken or the entry is incomplete; a ParameterError when its
  /// size knob does not fit its parameters.
  void add(CompressorEntry entry);
  bool contains(const std::string& name) const { return entries_.contains(name); }
  const CompressorEntry& get(const std::string& name) const;  ///< throws, listing known names
  std::vector<std::string> names() const;
  /// Removes an entry (a plugin that failed to load); unknown names are ignored.
  void remove(const std::string& name) { entries_.erase(name); }

  /// Validate parameters and construct.
  std::unique_ptr<Compressor> create(const std::string& name,
                                     const std::map<std::string, std::string>& params) const;
  /// Validate device options against the backend's device_params (ParameterError listing them).
  ParamSet device_options(const std::string& name,
                          const std::map<std::string, std::string>& options) const;
  /// Validate light options against the backend's light_params (ParameterError listing them).
  ParamSet light_options(const std::string& name,
                         const std::map<std::string, std::string>& options) const;

 private:
  std::map<std::string, CompressorEntry> entries_;
};

namespace detail {
/// Registers make()'s entry in the global registry through register_static() (plugin.h):
/// `api` is checked before make() runs.
void register_compressor_static(CompressorEntry (*make)(), int api) noexcept;
}  // namespace detail

/// Static registrar used by PRT_REGISTER_COMPRESSOR. Inline, so that `api` is the plugin API
/// version of the code that registers, not of the library that receives the entry.
struct CompressorRegistrar {
  explicit CompressorRegistrar(CompressorEntry (*make)(), int api = kPluginApiVersion) noexcept {
    detail::register_compressor_static(make, api);
  }
};

/// Upload `ct` to the device of `context` with its backend's device options (validated; the
/// defaults for keys not given). Returns nullptr when the backend has no OpenCL path.
std::unique_ptr<DeviceRelighter> upload_compressed(
    const CompressedTransfer& ct, ClContext& context,
    const std::map<std::string, std::string>& device_options = {});

/// Save a compressed transfer with a header naming its backend; load dispatches on it.
void save_compressed(const CompressedTransfer& ct, const std::filesystem::path& file);
std::unique_ptr<CompressedTransfer> load_compressed(const std::filesystem::path& file);

}  // namespace prt

#define PRT_REGISTER_COMPRESSOR(make_entry)                                      \
  static const ::prt::CompressorRegistrar PRT_CONCAT(prt_registrar_, __LINE__) { \
    &make_entry                                                                  \
  }
