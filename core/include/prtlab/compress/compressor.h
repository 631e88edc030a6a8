#pragma once
// The transfer-compressor interface. A backend implements two classes:
//
//   Compressor          built by name from validated parameters (see compressor_registry.h);
//                       compress() turns the exact pixel-basis transfer into a CompressedTransfer.
//   CompressedTransfer  the compressed representation: storage accounting, FLOP count, light
//                       projection into its basis, relight (C++ reference and OpenCL), save.
//
// Every backend is measured against the exact CSR product L* = T L in the pixel basis.
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/base/progress.h"
#include "prtlab/compress/params.h"
#include "prtlab/compress/storage_report.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/local_radiance.h"

namespace cl {
class Buffer;
}

namespace prt {

class TransferMatrix;
class ShTransfer;
struct Mesh;
class Btf;
class ArchiveWriter;
class ArchiveReader;
class ClContext;
class ParamSet;
class BrdfSignalSource;

/// What a compressor sees: the exact transfer, the bases it lives in, and whatever else its
/// registry entry declares it needs (CompressorEntry::inputs; prepare_scene() in
/// backend_input.h fills exactly that).
struct TransferInput {
  const TransferMatrix& transfer;  ///< pixel basis, (vertices * M) x N, exact
  const ShTransfer* sh = nullptr;  ///< SH transfer, when the entry asks for an SH order
  const CubemapLayout& cubemap;    ///< global basis (N = 6 R^2)
  const HemisphereGrid& grid;      ///< local basis (M = S^2)
  const Mesh* mesh = nullptr;      ///< the scene's mesh with parts and frames, when asked for
  /// The BTF of every mesh part (part order), when asked for.
  std::span<const std::shared_ptr<const Btf>> btfs = {};
  /// Where the BRDF-weighted signal of T comes from, when asked for (brdf_signal.h; null: a
  /// backend builds it through brdf_signal_rows() itself).
  BrdfSignalSource* brdf_signal = nullptr;
};

/// Light in a backend's basis: `basis` names it ("pixel", "haar", "sh5", "srbf642", ...).
struct LightCoeffs {
  std::string basis;
  std::vector<Rgb> values;
};

/// A compressed transfer resident on an OpenCL device.
class DeviceRelighter {
 public:
  virtual ~DeviceRelighter() = default;
  /// Relight on the device and read the result back into `out` (resized as needed).
  /// Returns the kernel time in milliseconds from OpenCL profiling events (all kernels of
  /// one relight, excluding the light upload and the read-back).
  virtual double relight(const LightCoeffs& light, LocalRadiance& out) = 0;
  /// The same, without reading back (for timing loops); returns kernel milliseconds.
  virtual double relight_on_device(const LightCoeffs& light) = 0;
  /// Bytes of device memory held.
  virtual std::uint64_t device_bytes() const = 0;
  /// The device buffer every relight writes L* into: rows x 3 floats (packed RGB, the layout of
  /// LocalRadiance::values, in output_basis()). The frame loop shades from it directly, so a
  /// light change never copies L* through the host. Valid after the first relight.
  virtual const cl::Buffer& output_buffer() const = 0;

  // ---- optional: relighting a subset of the vertices (docs/adding-a-compressor.md, "Relighting
  // a vertex subset"; the frame loop's culling, docs/rendering.md). A backend opts in by
  // overriding all three; the defaults relight every row.

  /// Whether relight_subset_on_device() leaves the rows outside the subset untouched.
  virtual bool supports_vertex_subset() const { return false; }
  /// The vertices (sorted, unique, < the vertex count: check_vertex_subset) the next
  /// relight_subset_on_device() calls relight. The backend uploads what it relights them from
  /// (an id list, the slices holding their rows), once per set rather than once per light.
  virtual void set_vertex_subset(std::span<const std::uint32_t> vertices) { (void)vertices; }
  /// Relight the subset's rows in output_buffer(), bit-identical to relight_on_device()'s values
  /// there; when supports_vertex_subset(), every other row keeps its value. Returns kernel ms.
  virtual double relight_subset_on_device(const LightCoeffs& light) {
    return relight_on_device(light);
  }
};

/// A quantity a backend measures of itself while compressing, which the harness records beside
/// its own measurements of the point (docs/adding-a-compressor.md, "Backend metrics").
struct BackendMetric {
  std::string name;  ///< snake_case, unique within the backend: the key in result.json
  double value = 0;
  std::string meaning;  ///< what is measured, over what, in which units
};

/// declared_error_bound() of a backend that guarantees no bound.
inline constexpr double kNoErrorBound = std::numeric_limits<double>::infinity();

class CompressedTransfer {
 public:
  virtual ~CompressedTransfer() = default;

  /// Registered backend name (what load_compressed() dispatches on).
  virtual std::string backend() const = 0;
  virtual StorageReport storage() const = 0;
  /// FLOPs of one relight for one colour channel, counted as the papers count them
  /// (a multiply-add is 2; a bicluster costs r + 2l - 1).
  virtual double flops_per_relight() const = 0;
  /// The norm declared_error_bound() is measured in, relative to the exact product T L over
  /// all rows and colour channels: ||T~ L - T L|| / ||T L||.
  enum class ErrorNorm { kRelativeL2, kRelativeL1 };
  /// The relative error of relight() vs the exact product that the backend guarantees for any
  /// non-negative light, in declared_error_norm(); 0 for lossless results (then only float
  /// rounding remains); +infinity (kNoErrorBound) for a fit that guarantees nothing of T L (it
  /// minimises another error, e.g. CPCA's squared error of T), which JSON writes as null.
  virtual double declared_error_bound() const = 0;
  virtual ErrorNorm declared_error_norm() const { return ErrorNorm::kRelativeL2; }
  /// The relative Frobenius error ||T~ - T||_F / ||T||_F the backend expects of itself, computed
  /// while compressing (a fit's residual, the dropped entries' norm), or nullopt when it
  /// declares none. Lossy backends without a proven bound report it so that the conformance
  /// suite can hold them to it: the measured error (transfer_error.h) must agree within 1e-3
  /// relative. Lossless results need not declare it (0 is checked from `lossless`).
  virtual std::optional<double> expected_frobenius_error() const { return std::nullopt; }
  /// Named numbers the backend measured while compressing (the error of its own input signal,
  /// which the harness's measurements against T cannot see); default none. They must survive
  /// save and load. The harness writes them into every point's record (result.json
  /// "backend_metrics", points.csv "backend_metrics", curves as "metrics.<name>").
  virtual std::vector<BackendMetric> backend_metrics() const { return {}; }
  /// Basis of the LocalRadiance relight() produces.
  virtual RadianceBasis output_basis() const { return RadianceBasis::kPixel; }

  /// Project a radiance cubemap into this backend's light basis.
  virtual LightCoeffs project_light(const Cubemap& radiance) const = 0;
  /// The same under run-time light options (CompressorEntry::light_params, validated, defaults
  /// filled in): a backend that declares some overrides this; callers go through
  /// project_light_with() (light_options.h). Default: the options change nothing.
  virtual LightCoeffs project_light_under(const Cubemap& radiance,
                                          const ParamSet& light_options) const {
    (void)light_options;
    return project_light(radiance);
  }
  /// C++ reference relight: out = T~ L (resized as needed).
  virtual void relight(const LightCoeffs& light, LocalRadiance& out) const = 0;
  /// Whether relight_vertices() relights only the given vertices (the frame loop's culling).
  /// A backend opts in by overriding both (docs/adding-a-compressor.md, "Relighting a vertex
  /// subset").
  virtual bool supports_vertex_subset() const { return false; }
  /// Relight the rows of `vertices` (sorted, unique, < the vertex count: check_vertex_subset)
  /// into `out`: bit-identical to relight()'s values there. When supports_vertex_subset(), every
  /// other row keeps its value (`out` is resized, and then zero, only when its shape is not
  /// relight()'s). Default: relight(), every row.
  virtual void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                                LocalRadiance& out) const {
    (void)vertices;
    relight(light, out);
  }
  /// OpenCL relight; a backend without a kernel returns nullptr (the conformance suite
  /// reports that as a failure for registered backends). The relighter may keep a reference
  /// to `context`, which must outlive it. `device_options` holds the backend's
  /// CompressorEntry::device_params (kernel variants, work sizes): they choose how the device
  /// computes, never what, so they are neither saved nor part of any cache key. Callers go
  /// through upload_compressed() (compressor_registry.h), which validates them.
  virtual std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                                  const ParamSet& device_options) const = 0;

  /// Serialise the backend's state (the registry writes the header and backend name).
  virtual void save(ArchiveWriter& archive) const = 0;
};

/// "relative_l2" / "relative_l1" (the JSON and report spelling).
inline std::string_view to_string(CompressedTransfer::ErrorNorm n) {
  return n == CompressedTransfer::ErrorNorm::kRelativeL1 ? "relative_l1" : "relative_l2";
}

/// Throws ParameterError naming `backend` unless T is (vertices * M) x N for the bases' M and N.
void check_transfer_shape(const TransferInput& input, std::string_view backend);
/// Throws ParameterError naming `backend` unless `light` is a pixel-basis light of `pixels`
/// values.
void check_pixel_light(const LightCoeffs& light, std::size_t pixels, std::string_view backend);

/// The pixel-basis light of `radiance` (its N values, the light of every backend whose light
/// basis is the cubemap); ParameterError naming `backend` unless N = `pixels`.
LightCoeffs pixel_light(const Cubemap& radiance, std::size_t pixels, std::string_view backend);

/// Throws ParameterError naming `backend` unless `vertices` is sorted, unique and below
/// `vertex_count` (what relight_vertices and set_vertex_subset accept).
void check_vertex_subset(std::span<const std::uint32_t> vertices, std::size_t vertex_count,
                         std::string_view backend);

class Compressor {
 public:
  virtual ~Compressor() = default;
  virtual std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                                       Progress& progress) const = 0;
};

}  // namespace prt
