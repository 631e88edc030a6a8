#pragma once
// Measured BTFs resampled onto prtlab's grids (docs/btf.md "Measured BTFs"): what the UTIA
// (utia_btf.h) and Bonn UBO (ubo_btf.h) readers share.
//
// A measured BTF is a tensor product of measured view directions x measured light directions,
// each pair holding a W x W texel tile. prtlab's Btf (btf.h) samples views and lights at the cell
// centres of two HemisphereGrids. Resampling is nearest neighbour in angle on the sphere: every
// grid direction takes the measured direction with the largest dot product (ties: the lowest
// measured index), separately for views and for lights, and the coverage (the largest and mean
// angle between a grid direction and the sample it took) is reported so that a sparse or
// partial measurement shows. No angular interpolation: the values are measured ones, never
// blended.
//
// Texels: a requested resolution U smaller than the measured W must divide it; each texel is
// the box-filter mean of its (W / U)^2 measured texels. The measured tile's texel (x, y) is the
// prtlab texel (x, y) (index y * W + x); each reader says how its files map onto (x, y).
//
// Units (LightCosine): prtlab's values carry the light's cell-mean cosine c_j (btf.h). A
// measurement carries either no cosine (an apparent BRDF) or the cosine of its own light
// direction theta_m. kCellMean divides out the measured cosine where the data has it and
// multiplies by c_j, so a measured Lambertian becomes prtlab's a / pi * c_j; kAsStored copies
// the stored values unchanged (times `scale`), which round-trips a prtlab writer bitwise.
//
// Values: every decoded value is checked. NaN or infinity (a dynamic-range decode that
// overflows, an infinite half, a NaN EXR sample) is an InputError naming the file, the measured
// view and light, the texel and the value. A negative value (noise, a truncated factorisation)
// is clamped to 0 before the box filter and counted (MeasuredCoverage::negative_clamped, with
// a warning). A value that only overflows float after the cosine and scale conversion is an
// InputError too.
//
// Size: the output BTF's resolution must be at most 4096 (Btf's limit), and the bytes the
// import needs (measured_import_bytes: the output BTF plus one decoded tile per worker thread)
// at most measured_import_byte_limit(), the machine's physical memory (16 GiB where it cannot
// be read). Both are checked before anything is allocated for them; an InputError naming the
// file and the size suggests --resolution, --view-side and --light-side.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/btf/btf.h"

namespace prt {

enum class LightCosine {
  kCellMean,  ///< stored / (measured cosine if the data has it) * c_j (the default)
  kAsStored,  ///< the stored values themselves
};
/// "cell-mean" / "as-stored"; ParameterError listing both otherwise.
LightCosine parse_light_cosine(const std::string& name);
std::string light_cosine_name(LightCosine cosine);

struct MeasuredImportOptions {
  int view_side = 12;  ///< V = view_side^2 grid views (1..64)
  int light_side = 8;  ///< M = light_side^2 grid lights (1..64)
  int resolution = 0;  ///< U; 0: the measured tile size W. Must divide W.
  double scale = 1.0;  ///< multiplies every value (finite, > 0)
  LightCosine cosine = LightCosine::kCellMean;
  std::string material;  ///< Btf::material(); empty: the reader's default (from the path)
};

/// How well the measured directions cover the grid, in degrees.
struct MeasuredCoverage {
  int measured_resolution = 0;  ///< W
  int measured_views = 0, measured_lights = 0;
  int views_used = 0, lights_used = 0;  ///< distinct measured directions some grid cell took
  double max_view_angle_deg = 0, mean_view_angle_deg = 0;
  double max_light_angle_deg = 0, mean_light_angle_deg = 0;
  int box_factor = 1;  ///< W / U
  /// Negative measured values (of the decoded tiles; each channel of each texel counts once
  /// per measured pair) that were clamped to 0.
  std::uint64_t negative_clamped = 0;
  std::uint64_t values_checked = 0;  ///< measured values decoded and checked
  nlohmann::json to_json() const;
};

struct MeasuredBtf {
  Btf btf;
  MeasuredCoverage coverage;
};

/// For every grid direction the index of the nearest measured direction (largest dot product,
/// ties to the lowest index) and the angle to it in radians. `measured` must not be empty and
/// holds unit vectors; entries flagged false in `usable` (optional, same size) are skipped.
struct NearestDirections {
  std::vector<int> index;
  std::vector<double> angle;
};
NearestDirections nearest_directions(const std::vector<Vec3d>& grid,
                                     const std::vector<Vec3d>& measured,
                                     const std::vector<bool>& usable = {});

/// Unit direction from a polar angle theta (from the normal) and an azimuth phi (from +t towards
/// +b), both in radians.
Vec3d direction_from_angles(double theta, double phi);

/// What a reader hands the resampler: the measured directions (unit, local frame) and a function
/// that fills the W x W x RGB tile (index (y * W + x) * 3 + c) of one measured (view, light)
/// pair. The function is called once per pair the grid needs, possibly from several threads at
/// once, and throws InputError for a bad file.
struct MeasuredSource {
  std::filesystem::path file;  ///< the file or directory, for errors
  int resolution = 0;          ///< W
  std::vector<Vec3d> views, lights;
  bool cosine_in_data = false;  ///< values carry cos(theta) of their measured light
  std::function<void(int view, int light, std::span<float> tile)> tile;
  /// The file a pair's values come from, for errors about them; empty: `file`.
  std::function<std::filesystem::path(int view, int light)> tile_file;
  std::string material;
  nlohmann::json parameters = nlohmann::json::object();
};

/// Bytes an import of a W x W measurement with `options` needs: the output BTF (U^2 V M RGB
/// floats) plus one decoded W x W tile and its box-filter sum per worker thread; saturates
/// instead of overflowing.
std::uint64_t measured_import_bytes(int measured_resolution, const MeasuredImportOptions& options);
/// The most measured_import_bytes an import may need: the physical memory, 16 GiB where it
/// cannot be read.
std::uint64_t measured_import_byte_limit();

/// Validates `options` for a W x W measurement before anything is allocated: ParameterError for
/// bad options (a resolution that does not divide W names W's divisors); InputError naming
/// `file` for an output resolution above 4096 or a size above measured_import_byte_limit().
/// Readers call it as soon as W is known; resample_measured calls it again.
void check_measured_import(const std::filesystem::path& file, int measured_resolution,
                           const MeasuredImportOptions& options);

/// Resamples a measured BTF onto the grids of `options` (check_measured_import first; values
/// checked as described above).
MeasuredBtf resample_measured(const MeasuredSource& source, const MeasuredImportOptions& options);

/// The factor by which writers divide a prtlab value to store it: c_j / cos(theta_m) for a format
/// whose data carries the measured cosine, c_j for one that stores an apparent BRDF, 1 for
/// kAsStored. `measured_cos` is the cosine of the direction as the file will record it.
double measured_value_factor(LightCosine cosine, bool cosine_in_data, double cell_mean_cosine,
                             double measured_cos);

}  // namespace prt
