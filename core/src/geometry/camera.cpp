#include "prtlab/geometry/camera.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"

namespace prt {
namespace {

constexpr int kMaxImageSide = 16384;

bool finite(const Vec3d& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::optional<double> to_double(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
    return std::nullopt;
  return v;
}

/// The frame of a camera looking along `forward` with the roll fixed by `up_hint`; both must
/// be finite, non-zero and not parallel (callers check and name the culprit).
bool make_frame(const Vec3d& forward_dir, const Vec3d& up_hint, CameraBasis& b) {
  const double fl = glm::length(forward_dir);
  const double ul = glm::length(up_hint);
  if (!(fl > 0) || !(ul > 0) || !std::isfinite(fl) || !std::isfinite(ul)) return false;
  b.forward = forward_dir / fl;
  const Vec3d r = glm::cross(b.forward, up_hint / ul);
  const double rl = glm::length(r);
  // Within about 0.06 degrees of parallel the roll is ill-defined.
  if (!(rl > 1e-3)) return false;
  b.right = r / rl;
  b.up = glm::cross(b.right, b.forward);
  return true;
}

}  // namespace

void Camera::validate() const {
  if (!finite(eye) || !finite(target) || !finite(up))
    throw ParameterError("camera: eye, target and up must be finite");
  if (!(fov_y_deg > 0 && fov_y_deg < 180))
    throw ParameterError(fmt::format("camera: fov {} degrees is outside (0, 180)", fov_y_deg));
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
    throw ParameterError(
        fmt::format("camera: image size {}x{} is outside [1, {}]", width, height, kMaxImageSide));
  if (eye == target) throw ParameterError("camera: eye and target are the same point");
  CameraBasis b;
  if (!make_frame(target - eye, up, b))
    throw ParameterError(fmt::format(
        "camera: up ({}, {}, {}) is zero or parallel to the viewing direction", up.x, up.y, up.z));
}

CameraBasis Camera::basis() const {
  validate();
  CameraBasis b;
  make_frame(target - eye, up, b);
  b.tan_half_fov_y = std::tan(0.5 * fov_y_deg * kPi / 180.0);
  b.aspect = static_cast<double>(width) / static_cast<double>(height);
  return b;
}

Vec3d Camera::ray_direction(double px, double py) const {
  const CameraBasis b = basis();
  const double sx = (2.0 * px / width - 1.0) * b.tan_half_fov_y * b.aspect;
  const double sy = (1.0 - 2.0 * py / height) * b.tan_half_fov_y;
  return glm::normalize(b.forward + sx * b.right + sy * b.up);
}

std::optional<Vec2d> Camera::project(const Vec3d& point) const {
  const CameraBasis b = basis();
  const Vec3d q = point - eye;
  const double z = glm::dot(q, b.forward);
  if (!(z > 0)) return std::nullopt;
  const double sx = glm::dot(q, b.right) / (z * b.tan_half_fov_y * b.aspect);
  const double sy = glm::dot(q, b.up) / (z * b.tan_half_fov_y);
  return Vec2d(0.5 * (sx + 1.0) * width, 0.5 * (1.0 - sy) * height);
}

void ViewPreset::validate() const {
  const auto fail = [&](const std::string& what) {
    throw ParameterError(fmt::format("view '{}': {}", name, what));
  };
  if (name.empty()) throw ParameterError("view preset without a name");
  if (eye.has_value() == from.has_value())
    fail("set exactly one of 'eye' (explicit position) and 'from' (framed direction)");
  if (eye && !finite(*eye)) fail("'eye' must be finite");
  if (target && !finite(*target)) fail("'target' must be finite");
  if (!(fov_y_deg > 0 && fov_y_deg < 180))
    fail(fmt::format("fov {} degrees is outside (0, 180)", fov_y_deg));
  if (!(fill > 0 && fill <= 1)) fail(fmt::format("fill {} is outside (0, 1]", fill));
  CameraBasis b;
  if (from && !make_frame(-*from, up, b)) fail("'from' is zero, not finite or parallel to 'up'");
  if (eye && target && !make_frame(*target - *eye, up, b))
    fail("'eye' equals 'target', or 'up' is parallel to the viewing direction");
}

ViewPreset automatic_view() {
  ViewPreset v;
  v.name = "auto";
  v.from = Vec3d(0.0, 0.35, 1.0);
  return v;
}

Camera resolve_view(const ViewPreset& view, std::span<const Vec3> points, int width, int height) {
  view.validate();
  Camera cam;
  cam.up = view.up;
  cam.fov_y_deg = view.fov_y_deg;
  cam.width = width;
  cam.height = height;
  if (view.target && view.eye) {
    cam.eye = *view.eye;
    cam.target = *view.target;
    cam.validate();
    return cam;
  }
  if (points.empty())
    throw ParameterError(fmt::format("view '{}': no scene points to frame", view.name));
  Vec3d lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const Vec3& p : points) {
    lo = glm::min(lo, Vec3d(p));
    hi = glm::max(hi, Vec3d(p));
  }
  Vec3d target = view.target.value_or(0.5 * (lo + hi));
  if (view.eye) {
    cam.eye = *view.eye;
    cam.target = target;
    cam.validate();
    return cam;
  }

  CameraBasis b;
  make_frame(-*view.from, view.up, b);
  const Vec3d back = -b.forward;  // from the target towards the eye
  const double tan_y = std::tan(0.5 * view.fov_y_deg * kPi / 180.0);
  const double tan_x = tan_y * width / static_cast<double>(height);
  const double radius = std::max(0.5 * glm::length(hi - lo), 1e-12);
  double distance = 0;
  // The distance that brings every point inside `fill` of the image is a maximum over points;
  // re-centring moves the target in the image plane, which changes that maximum a little, so a
  // few rounds converge (the fourth moves the centre by well under a pixel).
  const int rounds = view.target ? 1 : 6;
  for (int round = 0; round < rounds; ++round) {
    double need = -std::numeric_limits<double>::infinity();
    double z_max = need;
    for (const Vec3& p : points) {
      const Vec3d q = Vec3d(p) - target;
      const double z = glm::dot(q, back);
      const double x = std::abs(glm::dot(q, b.right)) / (view.fill * tan_x);
      const double y = std::abs(glm::dot(q, b.up)) / (view.fill * tan_y);
      need = std::max(need, z + std::max(x, y));
      z_max = std::max(z_max, z);
    }
    // A point exactly on the axis must still lie in front of the camera.
    distance = std::max(need, z_max + 1e-3 * radius);
    if (view.target) break;
    double sx_lo = std::numeric_limits<double>::infinity(), sx_hi = -sx_lo;
    double sy_lo = sx_lo, sy_hi = -sx_lo;
    for (const Vec3& p : points) {
      const Vec3d q = Vec3d(p) - target;
      const double depth = distance - glm::dot(q, back);
      const double sx = glm::dot(q, b.right) / (depth * tan_x);
      const double sy = glm::dot(q, b.up) / (depth * tan_y);
      sx_lo = std::min(sx_lo, sx), sx_hi = std::max(sx_hi, sx);
      sy_lo = std::min(sy_lo, sy), sy_hi = std::max(sy_hi, sy);
    }
    const double cx = 0.5 * (sx_lo + sx_hi), cy = 0.5 * (sy_lo + sy_hi);
    target += (cx * tan_x * distance) * b.right + (cy * tan_y * distance) * b.up;
  }
  cam.target = target;
  cam.eye = target + distance * back;
  cam.validate();
  return cam;
}

Vec3d parse_vec3(std::string_view text, std::string_view option) {
  Vec3d out;
  std::string_view rest = text;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = rest.find(',');
    const bool last = i == 2;
    if (last != (comma == std::string_view::npos)) {
      throw ParameterError(
          fmt::format("{}: '{}' is not three comma-separated numbers x,y,z", option, text));
    }
    const auto v = to_double(rest.substr(0, comma));
    if (!v)
      throw ParameterError(
          fmt::format("{}: '{}' is not three comma-separated numbers x,y,z", option, text));
    out[i] = *v;
    if (!last) rest.remove_prefix(comma + 1);
  }
  return out;
}

std::pair<int, int> parse_resolution(std::string_view text, std::string_view option) {
  const auto bad = [&] {
    return ParameterError(
        fmt::format("{}: '{}' is not an image size WxH (e.g. 640x480, each "
                    "side in [1, {}])",
                    option, text, kMaxImageSide));
  };
  const std::size_t x = text.find_first_of("xX");
  if (x == std::string_view::npos) throw bad();
  int w = 0, h = 0;
  const std::string_view ws = trim(text.substr(0, x)), hs = trim(text.substr(x + 1));
  const auto rw = std::from_chars(ws.data(), ws.data() + ws.size(), w);
  const auto rh = std::from_chars(hs.data(), hs.data() + hs.size(), h);
  if (ws.empty() || hs.empty() || rw.ec != std::errc() || rh.ec != std::errc() ||
      rw.ptr != ws.data() + ws.size() || rh.ptr != hs.data() + hs.size() || w < 1 || h < 1 ||
      w > kMaxImageSide || h > kMaxImageSide)
    throw bad();
  return {w, h};
}

double parse_number(std::string_view text, std::string_view option) {
  const auto v = to_double(text);
  if (!v) throw ParameterError(fmt::format("{}: '{}' is not a number", option, text));
  return *v;
}

CameraOverrides parse_camera_overrides(std::string_view eye, std::string_view target,
                                       std::string_view fov, std::string_view size) {
  CameraOverrides o;
  if (!eye.empty()) o.eye = parse_vec3(eye, "--eye");
  if (!target.empty()) o.target = parse_vec3(target, "--target");
  if (!fov.empty()) o.fov_y_deg = parse_number(fov, "--fov");
  if (!size.empty()) {
    const auto [w, h] = parse_resolution(size, "--size");
    o.width = w;
    o.height = h;
  }
  return o;
}

Camera apply_overrides(Camera camera, const CameraOverrides& o) {
  if (o.eye) camera.eye = *o.eye;
  if (o.target) camera.target = *o.target;
  if (o.up) camera.up = *o.up;
  if (o.fov_y_deg) camera.fov_y_deg = *o.fov_y_deg;
  if (o.width) camera.width = *o.width;
  if (o.height) camera.height = *o.height;
  camera.validate();
  return camera;
}

}  // namespace prt
