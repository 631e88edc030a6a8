#pragma once
// Pinhole camera, view presets and the camera options of the command line (docs/rendering.md).
//
// Image conventions: pixel (x, y) has x to the right and y downwards, row 0 at the top (as
// RgbImage stores it). Continuous image coordinates (px, py) put the top-left corner of the
// image at (0, 0) and the bottom-right corner at (width, height); the centre of pixel (x, y) is
// (x + 0.5, y + 0.5). The camera looks from `eye` towards `target`; `up` fixes the roll (the
// image's upward direction is `up` made orthogonal to the viewing direction). `fov_y_deg` is the
// full vertical field of view; the horizontal one follows from the aspect ratio width / height
// (square pixels).
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "prtlab/base/types.h"

namespace prt {

/// Orthonormal camera frame: `forward` points from the eye to the target, `right` and `up`
/// span the image plane (right = forward x up_hint, normalised; up = right x forward), so the
/// frame (right, up, -forward) is right-handed.
struct CameraBasis {
  Vec3d forward{0, 0, -1};
  Vec3d right{1, 0, 0};
  Vec3d up{0, 1, 0};
  double tan_half_fov_y = 0;  ///< tan(fov_y / 2)
  double aspect = 1;          ///< width / height
};

struct Camera {
  Vec3d eye{0, 0, 3};
  Vec3d target{0, 0, 0};
  Vec3d up{0, 1, 0};
  double fov_y_deg = 40;  ///< full vertical field of view, degrees, in (0, 180)
  int width = 640;
  int height = 480;

  /// Throws ParameterError naming the problem: non-finite values, eye == target, up parallel
  /// to the viewing direction, fov outside (0, 180), width or height outside [1, 16384].
  void validate() const;
  /// The camera frame (validates first).
  CameraBasis basis() const;
  /// Unit world-space direction of the ray through the continuous image point (px, py):
  /// (0, 0) is the top-left corner of the image, (width, height) the bottom-right one.
  Vec3d ray_direction(double px, double py) const;
  /// Unit direction of the ray through the centre of pixel (x, y).
  Vec3d pixel_direction(int x, int y) const { return ray_direction(x + 0.5, y + 0.5); }
  /// Continuous image coordinates of a world point, nullopt when it is not in front of the
  /// camera (depth <= 0). Inverse of ray_direction for points along the ray.
  std::optional<Vec2d> project(const Vec3d& point) const;
};

/// A named view of a scene (scene files: [[view]], see docs/scenes.md). Exactly one of `eye`
/// and `from` is set:
///  - `eye` (explicit): the camera sits at `eye` and looks at `target` (default: the centre of
///    the scene's bounding box);
///  - `from` (framed): the camera looks along -from (from points from the scene towards the
///    eye, any length) and its distance is chosen so that the scene's vertices fill `fill` of
///    the image in its tighter dimension; without `target` the view is also re-centred on the
///    projected vertices, so the object sits in the middle of the image.
struct ViewPreset {
  std::string name;
  std::optional<Vec3d> eye;
  std::optional<Vec3d> from;
  std::optional<Vec3d> target;
  Vec3d up{0, 1, 0};
  double fov_y_deg = 40;
  double fill = 0.9;  ///< framed views: fraction of the image spanned by the object, (0, 1]

  /// Throws ParameterError (naming the preset) when the fields are inconsistent.
  void validate() const;
};

/// The view used when a scene has no presets: framed from the front, slightly above
/// (from = (0, 0.35, 1)), 40 degrees, fill 0.9.
ViewPreset automatic_view();

/// Resolve a preset into a camera of the given size. `points` are the scene's vertex positions
/// (used for the bounding-box centre and for framing; may be empty only for an explicit preset
/// with a target). Throws ParameterError naming the preset on invalid input.
Camera resolve_view(const ViewPreset& view, std::span<const Vec3> points, int width = 640,
                    int height = 480);

// ---- command-line helpers (for the render command) ----------------------------------------

/// Parses "x,y,z" (three finite numbers, spaces allowed around them). ParameterError naming
/// `option` (e.g. "--eye") and the text otherwise.
Vec3d parse_vec3(std::string_view text, std::string_view option);
/// Parses "WxH" (e.g. "640x480"; each in [1, 16384]). ParameterError naming `option`.
std::pair<int, int> parse_resolution(std::string_view text, std::string_view option);
/// Parses a number (e.g. the value of --fov). ParameterError naming `option`.
double parse_number(std::string_view text, std::string_view option);

/// Free camera parameters from the command line; unset fields keep the preset's value.
struct CameraOverrides {
  std::optional<Vec3d> eye;
  std::optional<Vec3d> target;
  std::optional<Vec3d> up;
  std::optional<double> fov_y_deg;
  std::optional<int> width;
  std::optional<int> height;
  bool empty() const { return !eye && !target && !up && !fov_y_deg && !width && !height; }
};
/// Parse the options' texts (an empty string means "not given"): eye "x,y,z", target "x,y,z",
/// fov "degrees", size "WxH".
CameraOverrides parse_camera_overrides(std::string_view eye, std::string_view target,
                                       std::string_view fov, std::string_view size = {});
/// `camera` with the overrides applied, validated (ParameterError).
Camera apply_overrides(Camera camera, const CameraOverrides& overrides);

}  // namespace prt
