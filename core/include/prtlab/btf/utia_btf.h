#pragma once
// The UTIA BTF layout (docs/btf.md "Measured BTFs"): a directory with one square image per
// (light, view) pair, named by its angles in degrees as in the UTIA BTF database,
//
//   tl<theta_light>_pl<phi_light>_tv<theta_view>_pv<phi_view>.<png|exr>
//
// each angle digits with an optional decimal fraction (`tl015_pl000_tv030_pv060.png`,
// `tl7.5_pl0_tv0_pv0.exr`); the prefixes and the extension are case-insensitive. theta is the
// polar angle from the normal in [0, 90], phi the azimuth from +t towards +b in [0, 360).
// Files with another extension are ignored; a .png or .exr whose name does not match is an
// error, so that a misspelt name is never silently dropped.
//
// Images: the tile as seen from above, +t (texel x) to the right and +b (texel y) up, so pixel
// (column, row) is texel (column, W - 1 - row). PNG samples (8 or 16 bit, grey or RGB, alpha
// ignored) are linear: value / 255 or value / 65535, times the import scale; no sRGB decoding.
// EXR is float linear. The images are radiance images, so their values carry the cosine of their
// own light direction (measured_btf.h LightCosine).
//
// The set of lights and views is the set of distinct angle pairs in the names; every
// combination must be present (InputError naming the first missing file).
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "prtlab/btf/btf.h"
#include "prtlab/btf/measured_btf.h"

namespace prt {

/// Angles of one image, in degrees.
struct UtiaImageAngles {
  double theta_light = 0, phi_light = 0, theta_view = 0, phi_view = 0;
};
/// The angles of a file name (without directory) in the pattern above; nullopt otherwise
/// (an out-of-range angle also gives nullopt).
std::optional<UtiaImageAngles> parse_utia_image_name(std::string_view file_name);
/// `tl%03d_pl%03d_tv%03d_pv%03d.<extension>` of the angles rounded to integer degrees (phi
/// taken modulo 360).
std::string utia_image_name(const UtiaImageAngles& angles, std::string_view extension);

/// Reads a UTIA directory and resamples it (measured_btf.h). The default material name is
/// "utia:<directory name>". InputError naming the file for an unreadable, non-square or
/// differently sized image, a duplicate or missing pair, or a name outside the pattern.
MeasuredBtf read_utia_btf(const std::filesystem::path& directory,
                          const MeasuredImportOptions& options = {});

enum class UtiaImageFormat {
  kExr,    ///< float32 RGB EXR: exact
  kPng16,  ///< 16-bit RGB PNG: round(value / scale * 65535), clamped to [0, 65535]
};

struct UtiaWriteOptions {
  UtiaImageFormat format = UtiaImageFormat::kExr;
  double png_scale = 1.0;  ///< a PNG sample of 65535 stands for this value
  /// Must match the import's mode for a round trip: kCellMean writes b * cos(theta_m) / c_j with
  /// theta_m the angle as named, kAsStored writes b (bitwise round trip with EXR).
  LightCosine cosine = LightCosine::kCellMean;
};

/// What the writer did, for the CLI.
struct UtiaWriteReport {
  int images = 0;
  std::size_t clipped = 0;  ///< PNG samples clamped to [0, 65535] (non-finite ones count)
};

/// Writes one image per (grid light, grid view) pair at the grid's cell centre directions, the
/// angles rounded to integer degrees in the names, into `directory` (created; ParameterError if
/// it exists and is not empty, or if two directions round to the same name). The images are
/// written into a temporary directory renamed into place at the end.
UtiaWriteReport write_utia_btf(const Btf& btf, const std::filesystem::path& directory,
                               const UtiaWriteOptions& options = {});

}  // namespace prt
