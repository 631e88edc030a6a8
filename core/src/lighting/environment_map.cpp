#include "prtlab/lighting/environment_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/image/image_io.h"

namespace prt {
namespace fs = std::filesystem;

namespace {

// cos a - cos b without the cancellation of the direct difference near the poles.
double cos_difference(double a, double b) {
  return 2.0 * std::sin(0.5 * (a + b)) * std::sin(0.5 * (b - a));
}

// Signed solid angle seen through [0, x] x [0, y] on the plane at unit distance; the
// inclusion-exclusion of its four corners is the exact solid angle of a face rectangle.
double corner_area(double x, double y) {
  return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0));
}

double face_rect_solid_angle(double s0, double s1, double t0, double t1) {
  return corner_area(s1, t1) - corner_area(s0, t1) - corner_area(s1, t0) + corner_area(s0, t0);
}

double phi_of(const Vec3d& d) {
  return std::atan2(d.x, -d.z);
}

// ---------------------------------------------------------------------------------------------
// Exact overlap of a cube pixel with the lat-long texels.
//
// Work in the plane (phi, z = cos theta): solid angle is plain area there (dω = dphi dz) and a
// texel is an axis-aligned rectangle. A cube pixel is the intersection of four hemispheres
// n . d >= 0 (its edges are great-circle arcs). On the half-meridian at phi,
//   n . d = sin(theta) g(phi) + n_y cos(theta),   g(phi) = n_x sin(phi) - n_z cos(phi),
// so each constraint is one-sided in z: z >= b(phi) when n_y > 0, z <= b(phi) when n_y < 0,
// with b(phi) = -sgn(n_y) g / sqrt(n_y^2 + g^2); and when n_y = 0 (a meridian edge) it only
// restricts phi (g >= 0). b has the closed-form primitive
//   B(phi) = sgn(n_y) atan2(n_x cos(phi) + n_z sin(phi), sqrt(n_y^2 + g^2)).
// For a row band [z_lo, z_hi] the overlap density in phi is
//   (min(z_hi, min_upper b) - max(z_lo, max_lower b))_+ * [meridian constraints hold],
// which is a single closed form between breakpoints (pairwise great-circle intersections,
// crossings of a boundary with z_lo or z_hi, zeros of meridian g). Integrating it over each
// texel column gives the overlap areas exactly; they sum to the texel's solid angle over the
// pixels and to the pixel's solid angle over the texels.
// ---------------------------------------------------------------------------------------------

// An angle with its sine and cosine, evaluated once per breakpoint and shared by all edges.
struct Angle {
  double phi = 0, s = 0, c = 1;
  static Angle of(double phi) { return {phi, std::sin(phi), std::cos(phi)}; }
};

struct Constraint {
  double nx = 0, ny = 0, nz = 0;
  bool meridian = false;
  double sign = 1;  // sgn(n_y)

  double g(const Angle& a) const { return nx * a.s - nz * a.c; }
  double boundary(const Angle& a) const {
    const double gg = g(a);
    return -sign * gg / std::sqrt(ny * ny + gg * gg);
  }
  double primitive(const Angle& a) const {
    const double gg = g(a);
    return sign * std::atan2(nx * a.c + nz * a.s, std::sqrt(ny * ny + gg * gg));
  }
};

struct FaceBasis {
  Vec3d e, a, b;  // direction(s, t) ∝ e + s a + t b
};

// Read the face table back from CubemapLayout so the two can never disagree: the table's
// entries are 0 and +-1, which the rounding recovers exactly.
std::array<FaceBasis, 6> face_bases() {
  std::array<FaceBasis, 6> bases;
  const double root2 = std::sqrt(2.0);
  auto round3 = [](const Vec3d& v) {
    return Vec3d(std::round(v.x), std::round(v.y), std::round(v.z));
  };
  for (int f = 0; f < 6; ++f) {
    const Vec3d e = round3(CubemapLayout::face_direction(f, 0.0, 0.0));
    bases[f] = {e, round3(CubemapLayout::face_direction(f, 1.0, 0.0) * root2) - e,
                round3(CubemapLayout::face_direction(f, 0.0, 1.0) * root2) - e};
  }
  return bases;
}

class PixelOverlap {
 public:
  PixelOverlap(const FaceBasis& fb, double s0, double s1, double t0, double t1) {
    const double sigma = glm::dot(glm::cross(fb.e, fb.b), fb.a) > 0 ? 1.0 : -1.0;
    // Inward normals of the edges s = s0, s = s1, t = t0, t = t1: the plane of the edge s = s0
    // holds e + s0 a and b, and ((e + s0 a) x b) . (e + s a + t b) = (s - s0) ((e x b) . a),
    // so sigma = sgn((e x b) . a) makes it positive inside (likewise for t, with -sigma).
    const Vec3d n[4] = {
        sigma * glm::cross(fb.e + s0 * fb.a, fb.b), -sigma * glm::cross(fb.e + s1 * fb.a, fb.b),
        -sigma * glm::cross(fb.e + t0 * fb.b, fb.a), sigma * glm::cross(fb.e + t1 * fb.b, fb.a)};
    bool all_nonneg = true, all_nonpos = true;
    for (int i = 0; i < 4; ++i) {
      Constraint& c = c_[i];
      c.nx = n[i].x;
      c.ny = n[i].y;
      c.nz = n[i].z;
      // Meridian edges have n_y = 0 exactly (their normals are built from exact 0 entries);
      // the tolerance only guards against a future change in how normals are formed.
      c.meridian = std::abs(c.ny) <= 1e-12 * glm::length(n[i]);
      if (c.meridian) c.ny = 0.0;
      c.sign = c.ny >= 0 ? 1.0 : -1.0;
      all_nonneg = all_nonneg && c.ny >= 0.0;
      all_nonpos = all_nonpos && c.ny <= 0.0;
    }
    north_ = all_nonneg;  // +Y inside or on the boundary
    south_ = all_nonpos;

    // Row-independent breakpoints, as angles in (-pi, pi].
    for (int i = 0; i < 4; ++i) {
      if (c_[i].meridian) {
        const double alpha = std::atan2(c_[i].nz, c_[i].nx);
        base_breaks_.push_back(alpha);
        base_breaks_.push_back(alpha > 0 ? alpha - kPi : alpha + kPi);
      }
      for (int j = i + 1; j < 4; ++j) {
        const Vec3d m = glm::cross(n[i], n[j]);
        if (std::hypot(m.x, m.z) <= 1e-14 * glm::length(m)) continue;  // meet at a pole
        base_breaks_.push_back(std::atan2(m.x, -m.z));
        base_breaks_.push_back(std::atan2(-m.x, m.z));
      }
    }

    const Vec3d corners[4] = {
        glm::normalize(fb.e + s0 * fb.a + t0 * fb.b), glm::normalize(fb.e + s1 * fb.a + t0 * fb.b),
        glm::normalize(fb.e + s1 * fb.a + t1 * fb.b), glm::normalize(fb.e + s0 * fb.a + t1 * fb.b)};
    // Range of y over the pixel: corners, the extremes of each edge arc that fall inside the
    // arc, and the poles when the pixel contains them.
    ymin_ = 1.0;
    ymax_ = -1.0;
    for (int i = 0; i < 4; ++i) {
      const Vec3d& p = corners[i];
      const Vec3d& q = corners[(i + 1) % 4];
      ymin_ = std::min(ymin_, p.y);
      ymax_ = std::max(ymax_, p.y);
      const Vec3d m = glm::cross(p, q);
      const double ml = glm::length(m);
      if (ml <= 0) continue;
      const Vec3d mh = m / ml;
      Vec3d top = Vec3d(0, 1, 0) - mh.y * mh;
      const double tl = glm::length(top);
      if (tl <= 1e-15) continue;  // the arc lies on the equator
      top /= tl;
      for (const Vec3d& x : {top, -top}) {
        if (glm::dot(glm::cross(p, x), m) >= 0 && glm::dot(glm::cross(x, q), m) >= 0) {
          ymin_ = std::min(ymin_, x.y);
          ymax_ = std::max(ymax_, x.y);
        }
      }
    }
    if (north_) ymax_ = 1.0;
    if (south_) ymin_ = -1.0;

    if (!north_ && !south_) {
      // Away from the poles phi is monotonic along every edge arc, so the corners bound it.
      centre_phi_ = phi_of(fb.e + 0.5 * (s0 + s1) * fb.a + 0.5 * (t0 + t1) * fb.b);
      lo_phi_ = hi_phi_ = 0;
      for (const Vec3d& p : corners) {
        double d = phi_of(p) - centre_phi_;
        if (d > kPi) d -= kTwoPi;
        if (d < -kPi) d += kTwoPi;
        lo_phi_ = std::min(lo_phi_, d);
        hi_phi_ = std::max(hi_phi_, d);
      }
    }
  }

  bool full_phi() const { return north_ || south_; }
  double ymin() const { return ymin_; }
  double ymax() const { return ymax_; }
  double phi_lo() const { return centre_phi_ + lo_phi_; }
  double phi_hi() const { return centre_phi_ + hi_phi_; }

  /// Collect the breakpoints for the row band [zlo, zhi] inside (wa, wb), sorted.
  void row_breaks(double zlo, double zhi, double wa, double wb, std::vector<Angle>& out) const {
    out.clear();
    auto add = [&](double phi) {
      // Every candidate is an angle known modulo 2 pi; add each copy inside the window.
      const double k0 = std::ceil((wa - phi) / kTwoPi), k1 = std::floor((wb - phi) / kTwoPi);
      for (double k = k0; k <= k1; k += 1.0) {
        const double x = phi + k * kTwoPi;
        if (x > wa && x < wb) out.push_back(Angle::of(x));
      }
    };
    for (double phi : base_breaks_) add(phi);
    for (const Constraint& c : c_) {
      if (c.meridian) continue;
      const double rho2 = c.nx * c.nx + c.nz * c.nz;
      if (rho2 <= 1e-300) continue;  // the equator: a constant boundary, no crossing needed
      for (double z : {zlo, zhi}) {
        // Points d = (x, z, w) with n . d = 0 and x^2 + w^2 = 1 - z^2: a line meets a circle.
        const double r2 = 1.0 - z * z;
        const double k = -c.ny * z / rho2;  // foot of the line: k (n_x, n_z)
        const double h2 = r2 - k * k * rho2;
        if (h2 < 0) continue;
        const double h = std::sqrt(h2 / rho2);
        const double fx = k * c.nx, fz = k * c.nz;
        add(std::atan2(fx - h * c.nz, -(fz + h * c.nx)));
        add(std::atan2(fx + h * c.nz, -(fz - h * c.nx)));
      }
    }
    std::sort(out.begin(), out.end(), [](const Angle& a, const Angle& b) { return a.phi < b.phi; });
  }

  /// Integral over [x0, x1] of the overlap density in the band [zlo, zhi]; no breakpoint may
  /// lie strictly inside (x0, x1).
  double piece(const Angle& x0, const Angle& x1, double zlo, double zhi) const {
    if (!(x1.phi > x0.phi)) return 0.0;
    const Angle m = Angle::of(0.5 * (x0.phi + x1.phi));
    double top = zhi, bottom = zlo;
    int top_i = -1, bottom_i = -1;
    for (int i = 0; i < 4; ++i) {
      const Constraint& c = c_[i];
      if (c.meridian) {
        if (c.g(m) < 0) return 0.0;
        continue;
      }
      const double z = c.boundary(m);
      if (c.ny > 0) {
        if (z > bottom) bottom = z, bottom_i = i;
      } else if (z < top) {
        top = z, top_i = i;
      }
    }
    if (top <= bottom) return 0.0;
    const double upper =
        top_i < 0 ? zhi * (x1.phi - x0.phi) : c_[top_i].primitive(x1) - c_[top_i].primitive(x0);
    const double lower = bottom_i < 0 ? zlo * (x1.phi - x0.phi)
                                      : c_[bottom_i].primitive(x1) - c_[bottom_i].primitive(x0);
    return std::max(upper - lower, 0.0);
  }

 private:
  std::array<Constraint, 4> c_;
  std::vector<double> base_breaks_;
  bool north_ = false, south_ = false;
  double ymin_ = -1, ymax_ = 1;
  double centre_phi_ = 0, lo_phi_ = -kPi, hi_phi_ = kPi;
};

}  // namespace

double LatLongImage::texel_solid_angle(int row) const {
  PRT_DCHECK(row >= 0 && row < height, "row {} out of range", row);
  return kTwoPi / width * cos_difference(kPi * row / height, kPi * (row + 1) / height);
}

Vec3d LatLongImage::total_power() const {
  PRT_CHECK(texels.size() == static_cast<std::size_t>(width) * height,
            "lat-long image has {} texels, {} x {} expected", texels.size(), width, height);
  Vec3d power{0.0};
  for (int r = 0; r < height; ++r) {
    Vec3d row{0.0};
    for (int c = 0; c < width; ++c) row += Vec3d(at(c, r));
    power += row * texel_solid_angle(r);
  }
  return power;
}

Vec3d latlong_direction(double u, double v) {
  const double phi = kTwoPi * u, theta = kPi * v;
  const double st = std::sin(theta);
  return {st * std::sin(phi), std::cos(theta), -st * std::cos(phi)};
}

Vec2d direction_to_latlong(const Vec3d& d) {
  const double horizontal = std::hypot(d.x, d.z);
  const double theta = std::atan2(horizontal, d.y);
  double phi = horizontal > 0 ? std::atan2(d.x, -d.z) : 0.0;
  if (phi < 0) phi += kTwoPi;
  double u = phi / kTwoPi;
  if (u >= 1.0) u = 0.0;  // phi just below 0 rounds to 2 pi
  return {u, theta / kPi};
}

LatLongImage load_latlong_exr(const fs::path& file, EnvLoadReport* report) {
  RgbImage image = read_exr(file);
  LatLongImage out;
  out.width = image.width;
  out.height = image.height;
  out.texels = std::move(image.pixels);
  std::size_t invalid = 0, nonfinite = 0;
  float most_negative = 0.f;
  for (Rgb& t : out.texels) {
    bool bad = false, inf_or_nan = false;
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(t[c])) {
        inf_or_nan = true;
      } else if (t[c] < 0.f) {
        most_negative = std::min(most_negative, t[c]);
      } else {
        continue;
      }
      t[c] = 0.f;
      bad = true;
    }
    invalid += bad;
    nonfinite += inf_or_nan;
  }
  if (invalid > 0) {
    // Small negatives are common in camera HDRs (noise, colour-space conversion); the most
    // negative value tells the user whether that is all it is.
    log_warn_named(
        "invalid-radiance",
        "{}: {} of {} texels had NaN, Inf or negative values ({} non-finite, most negative "
        "{:.3g}); set to 0",
        file.string(), invalid, out.texels.size(), nonfinite, most_negative);
  }
  float peak = 0.f;
  for (const Rgb& t : out.texels) peak = std::max({peak, t[0], t[1], t[2]});
  if (peak > kRadianceLimit)
    throw InputError(file, fmt::format("radiance up to {:.3g} is beyond what a float relight can "
                                       "sum without overflowing (at most {:.0e}); scale the map "
                                       "down",
                                       peak, kRadianceLimit));
  if (peak > kRadianceWarnLimit)
    log_warn_named("radiance-range",
                   "{}: radiance up to {:.3g} (above {:.0e}): float relights keep their "
                   "relative accuracy, but squared-error sums in float may overflow",
                   file.string(), peak, kRadianceWarnLimit);
  const bool two_to_one = out.width == 2 * out.height;
  if (!two_to_one)
    log_warn_named("latlong-aspect",
                   "{}: {} x {} is not a 2:1 lat-long map; it is stretched to cover the sphere",
                   file.string(), out.width, out.height);
  if (report) {
    report->invalid_texels = invalid;
    report->max_radiance = peak;
    report->aspect_2_to_1 = two_to_one;
  }
  return out;
}

Cubemap resample_to_cubemap(const LatLongImage& image, int resolution) {
  PRT_CHECK(image.width > 0 && image.height > 0 &&
                image.texels.size() == static_cast<std::size_t>(image.width) * image.height,
            "lat-long image has {} texels, {} x {} expected", image.texels.size(), image.width,
            image.height);
  Cubemap cubemap(resolution);
  const int r = resolution, w = image.width, h = image.height;
  const auto bases = face_bases();
  // Row boundaries z_r = cos(pi r / H), exact at the poles.
  std::vector<double> zrow(h + 1);
  for (int i = 0; i <= h; ++i) zrow[i] = std::cos(kPi * i / h);
  zrow[0] = 1.0;
  zrow[h] = -1.0;
  const double col_width = kTwoPi / w;
  std::vector<double> col_sin(w), col_cos(w);
  for (int c = 0; c < w; ++c)
    col_sin[c] = std::sin(c * col_width), col_cos[c] = std::cos(c * col_width);
  // Column boundary c (not wrapped: a window may start below 0 or end past 2 pi).
  auto col_angle = [&](int c) {
    const int m = ((c % w) + w) % w;
    return Angle{c * col_width, col_sin[m], col_cos[m]};
  };

  tbb::parallel_for(
      tbb::blocked_range<int>(0, cubemap.layout.pixel_count(), 16),
      [&](const tbb::blocked_range<int>& range) {
        std::vector<Angle> breaks;
        for (int k = range.begin(); k != range.end(); ++k) {
          const int face = k / (r * r), y = (k / r) % r, x = k % r;
          const PixelOverlap px(bases[face], 2.0 * x / r - 1.0, 2.0 * (x + 1) / r - 1.0,
                                2.0 * y / r - 1.0, 2.0 * (y + 1) / r - 1.0);
          // One row/column of margin on each side absorbs rounding in the bounds; extra texels
          // simply contribute zero overlap.
          const int r0 = std::max(
              0, static_cast<int>(std::floor(std::acos(std::min(px.ymax(), 1.0)) / kPi * h)) - 1);
          const int r1 = std::min(
              h - 1,
              static_cast<int>(std::floor(std::acos(std::max(px.ymin(), -1.0)) / kPi * h)) + 1);
          int c0 = 0, c1 = w - 1;
          if (!px.full_phi()) {
            c0 = static_cast<int>(std::floor(px.phi_lo() / col_width)) - 1;
            c1 = static_cast<int>(std::floor(px.phi_hi() / col_width)) + 1;
            if (c1 - c0 + 1 >= w) c0 = 0, c1 = w - 1;
          }
          const double wa = c0 * col_width, wb = (c1 + 1) * col_width;
          Vec3d sum{0.0};
          for (int row = r0; row <= r1; ++row) {
            const double zhi = zrow[row], zlo = zrow[row + 1];
            px.row_breaks(zlo, zhi, wa, wb, breaks);
            std::size_t b = 0;
            const Rgb* texels = &image.texels[static_cast<std::size_t>(row) * w];
            Angle x0 = col_angle(c0);
            for (int c = c0; c <= c1; ++c) {
              const Angle a1 = col_angle(c + 1);
              double area = 0.0;
              while (b < breaks.size() && breaks[b].phi < a1.phi) {
                area += px.piece(x0, breaks[b], zlo, zhi);
                if (breaks[b].phi > x0.phi) x0 = breaks[b];
                ++b;
              }
              area += px.piece(x0, a1, zlo, zhi);
              x0 = a1;
              if (area > 0.0) sum += area * Vec3d(texels[((c % w) + w) % w]);
            }
          }
          cubemap.radiance[k] = Rgb(sum / cubemap.layout.solid_angle(k));
        }
      });
  return cubemap;
}

double cap_area_above_plane(double radius, double elevation) {
  PRT_CHECK(radius > 0 && radius <= kPi / 2 + 1e-12, "cap radius {} out of (0, pi/2]", radius);
  const double full = kTwoPi * (1.0 - std::cos(radius));
  if (elevation >= radius) return full;
  if (elevation <= -radius) return 0.0;
  // Gauss-Bonnet on the region bounded by the cap's circle (geodesic curvature cot r, kept
  // over an azimuth of 2 psi) and the great circle (curvature 0), meeting at interior angle
  // pi - gamma where gamma is the angle between the two circles' normals.
  const double gamma = std::acos(std::clamp(std::sin(elevation) / std::sin(radius), -1.0, 1.0));
  const double psi = std::acos(std::clamp(-std::tan(elevation) / std::tan(radius), -1.0, 1.0));
  return std::clamp(2.0 * (kPi - gamma) - 2.0 * std::cos(radius) * psi, 0.0, full);
}

namespace {
// SunSky::radiance for unit directions, with the sun's axis and cone precomputed (the image
// generators call it millions of times).
struct SunSkyEval {
  explicit SunSkyEval(const SunSky& e)
      : env(e), axis(glm::normalize(e.sun_dir)), cos_radius(std::cos(e.sun_radius_rad)) {}
  Rgb operator()(const Vec3d& unit) const {
    if (glm::dot(unit, axis) >= cos_radius) return env.sun;
    return unit.y > 0 ? env.sky : env.ground;
  }
  const SunSky& env;
  Vec3d axis;
  double cos_radius;
};
}  // namespace

Rgb SunSky::radiance(const Vec3d& d) const {
  return SunSkyEval(*this)(glm::normalize(d));
}

Vec3d SunSky::total_power() const {
  const Vec3d s = glm::normalize(sun_dir);
  const double cap = kTwoPi * (1.0 - std::cos(sun_radius_rad));
  const double above = cap_area_above_plane(sun_radius_rad, std::asin(std::clamp(s.y, -1.0, 1.0)));
  return kTwoPi * (Vec3d(sky) + Vec3d(ground)) + (Vec3d(sun) - Vec3d(sky)) * above +
         (Vec3d(sun) - Vec3d(ground)) * (cap - above);
}

LatLongImage SunSky::to_latlong(int width, int height, int supersample) const {
  PRT_CHECK(width > 0 && height > 0 && supersample > 0, "bad lat-long size {} x {} (x{})", width,
            height, supersample);
  LatLongImage img;
  img.width = width;
  img.height = height;
  img.texels.resize(static_cast<std::size_t>(width) * height);
  const int ss = supersample;
  const SunSkyEval eval(*this);
  tbb::parallel_for(0, height, [&](int row) {
    // Sub-rows differ in solid angle; sub-columns of a sub-row do not.
    std::vector<double> weight(ss);
    for (int j = 0; j < ss; ++j) {
      weight[j] = cos_difference(kPi * (row + double(j) / ss) / height,
                                 kPi * (row + double(j + 1) / ss) / height);
    }
    for (int col = 0; col < width; ++col) {
      Vec3d sum{0.0};
      double wsum = 0.0;
      for (int j = 0; j < ss; ++j) {
        for (int i = 0; i < ss; ++i) {
          const Vec3d d =
              latlong_direction((col + (i + 0.5) / ss) / width, (row + (j + 0.5) / ss) / height);
          sum += weight[j] * Vec3d(eval(d));
          wsum += weight[j];
        }
      }
      img.texels[static_cast<std::size_t>(row) * width + col] = Rgb(sum / wsum);
    }
  });
  return img;
}

Cubemap SunSky::to_cubemap(int resolution, int supersample) const {
  PRT_CHECK(supersample > 0, "supersample must be positive, got {}", supersample);
  Cubemap cubemap(resolution);
  const int r = resolution, ss = supersample;
  const auto bases = face_bases();
  const SunSkyEval eval(*this);
  tbb::parallel_for(0, cubemap.layout.pixel_count(), [&](int k) {
    const int face = k / (r * r), y = (k / r) % r, x = k % r;
    const FaceBasis& fb = bases[face];
    Vec3d sum{0.0};
    double wsum = 0.0;
    for (int j = 0; j < ss; ++j) {
      const double t0 = 2.0 * (y + double(j) / ss) / r - 1.0,
                   t1 = 2.0 * (y + double(j + 1) / ss) / r - 1.0;
      for (int i = 0; i < ss; ++i) {
        const double s0 = 2.0 * (x + double(i) / ss) / r - 1.0,
                     s1 = 2.0 * (x + double(i + 1) / ss) / r - 1.0;
        const double w = face_rect_solid_angle(s0, s1, t0, t1);
        sum +=
            w * Vec3d(eval(glm::normalize(fb.e + 0.5 * (s0 + s1) * fb.a + 0.5 * (t0 + t1) * fb.b)));
        wsum += w;
      }
    }
    cubemap.radiance[k] = Rgb(sum / wsum);
  });
  return cubemap;
}

}  // namespace prt
