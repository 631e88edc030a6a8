#include "prtlab/sphere/cubemap.h"

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"

namespace prt {

namespace {

// Signed area of the spherical region seen through the rectangle [0, x] x [0, y] of the
// plane at unit distance (gnomonic projection). Inclusion-exclusion over a pixel's four
// corners gives its exact solid angle.
double corner_area(double x, double y) {
  return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0));
}

int pixel_coord(double s, int r) {
  // floor, then clamp: s = +1 exactly (a face edge) belongs to the last pixel, and rounding
  // in face_coords may put s a hair outside [-1, 1].
  const int i = static_cast<int>(std::floor((s + 1.0) * 0.5 * r));
  return std::clamp(i, 0, r - 1);
}

}  // namespace

CubemapLayout::CubemapLayout(int resolution) : r_(resolution) {
  if (resolution < 1 || resolution > 8192) {
    throw ParameterError(
        fmt::format("cubemap resolution must be in [1, 8192], got {}", resolution));
  }
  const int n = pixel_count();
  directions_.resize(n);
  solid_angles_.resize(n);

  // The solid angle depends only on (x, y) within a face (every face is the same gnomonic
  // grid, rotated or reflected), so it is computed once on the (R+1)^2 corner grid.
  std::vector<double> corner(static_cast<std::size_t>(r_ + 1) * (r_ + 1));
  auto coord = [&](int i) { return 2.0 * i / r_ - 1.0; };
  for (int y = 0; y <= r_; ++y)
    for (int x = 0; x <= r_; ++x) corner[y * (r_ + 1) + x] = corner_area(coord(x), coord(y));
  std::vector<double> face_omega(static_cast<std::size_t>(r_) * r_);
  for (int y = 0; y < r_; ++y) {
    for (int x = 0; x < r_; ++x) {
      const auto c = [&](int cx, int cy) { return corner[cy * (r_ + 1) + cx]; };
      face_omega[y * r_ + x] = c(x + 1, y + 1) - c(x, y + 1) - c(x + 1, y) + c(x, y);
    }
  }

  for (int face = 0; face < 6; ++face) {
    for (int y = 0; y < r_; ++y) {
      const double t = (2.0 * y + 1.0) / r_ - 1.0;
      for (int x = 0; x < r_; ++x) {
        const double s = (2.0 * x + 1.0) / r_ - 1.0;
        const int k = index(face, x, y);
        directions_[k] = face_direction(face, s, t);
        solid_angles_[k] = face_omega[y * r_ + x];
      }
    }
  }
}

Vec3d CubemapLayout::direction(int k) const {
  PRT_DCHECK(k >= 0 && k < pixel_count(), "pixel {} out of range", k);
  return directions_[k];
}

double CubemapLayout::solid_angle(int k) const {
  PRT_DCHECK(k >= 0 && k < pixel_count(), "pixel {} out of range", k);
  return solid_angles_[k];
}

Vec3d CubemapLayout::face_direction(int face, double s, double t) {
  Vec3d d{0.0};
  switch (face) {
    case 0:
      d = {1.0, -t, -s};
      break;
    case 1:
      d = {-1.0, -t, s};
      break;
    case 2:
      d = {s, 1.0, t};
      break;
    case 3:
      d = {s, -1.0, -t};
      break;
    case 4:
      d = {s, -t, 1.0};
      break;
    case 5:
      d = {-s, -t, -1.0};
      break;
    default:
      PRT_CHECK(false, "cubemap face {} out of range", face);
  }
  return glm::normalize(d);
}

void CubemapLayout::face_coords(const Vec3d& d, int& face, double& s, double& t) {
  const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  PRT_DCHECK(ax + ay + az > 0.0 && std::isfinite(ax + ay + az),
             "direction must be finite, non-zero");
  // Ties (face edges and corners) go to the first face in the order X, Y, Z; either choice
  // gives the same point since s or t is then +-1 on both faces.
  if (ax >= ay && ax >= az) {
    const double inv = 1.0 / ax;
    face = d.x >= 0.0 ? 0 : 1;
    s = (face == 0 ? -d.z : d.z) * inv;
    t = -d.y * inv;
  } else if (ay >= az) {
    const double inv = 1.0 / ay;
    face = d.y >= 0.0 ? 2 : 3;
    s = d.x * inv;
    t = (face == 2 ? d.z : -d.z) * inv;
  } else {
    const double inv = 1.0 / az;
    face = d.z >= 0.0 ? 4 : 5;
    s = (face == 4 ? d.x : -d.x) * inv;
    t = -d.y * inv;
  }
}

int CubemapLayout::pixel_of(const Vec3d& d) const {
  int face = 0;
  double s = 0.0, t = 0.0;
  face_coords(d, face, s, t);
  return index(face, pixel_coord(s, r_), pixel_coord(t, r_));
}

Vec3d Cubemap::total_power() const {
  PRT_CHECK(radiance.size() == static_cast<std::size_t>(layout.pixel_count()),
            "cubemap radiance has {} entries, layout needs {}", radiance.size(),
            layout.pixel_count());
  const auto omega = layout.solid_angles();
  Vec3d sum{0.0};
  for (std::size_t k = 0; k < radiance.size(); ++k) sum += Vec3d(radiance[k]) * omega[k];
  return sum;
}

std::vector<Rgb> Cubemap::light_vector() const {
  PRT_CHECK(radiance.size() == static_cast<std::size_t>(layout.pixel_count()),
            "cubemap radiance has {} entries, layout needs {}", radiance.size(),
            layout.pixel_count());
  const auto omega = layout.solid_angles();
  std::vector<Rgb> l(radiance.size());
  for (std::size_t k = 0; k < radiance.size(); ++k) l[k] = Rgb(Vec3d(radiance[k]) * omega[k]);
  return l;
}

}  // namespace prt
