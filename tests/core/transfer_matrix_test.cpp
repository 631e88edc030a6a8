// The exact pixel-basis transfer matrix: energy on an open plane within the derived horizon
// bound, the structure of the blocks (one non-zero per column, values k / s^2), CSR
// validation, determinism, and invariance under a rotation of the whole scene.
#include "prtlab/transfer/transfer_matrix.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "prtlab/base/error.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/distributed_transfer.h"
#include "prtlab/transfer/visibility.h"

namespace prt {
namespace {

Mat3d rotation(const Vec3d& axis, double angle) {
  const Vec3d a = glm::normalize(axis);
  const double c = std::cos(angle), s = std::sin(angle);
  // Rodrigues, column-major (glm): m[col][row].
  Mat3d m(1.0);
  for (int i = 0; i < 3; ++i) {
    Vec3d e(0.0);
    e[i] = 1.0;
    m[i] = e * c + glm::cross(a, e) * s + a * glm::dot(a, e) * (1.0 - c);
  }
  return m;
}

void transform(Mesh& mesh, const Mat3d& q, const Vec3d& offset = Vec3d(0.0)) {
  for (auto& p : mesh.positions) p = Vec3(q * Vec3d(p) + offset);
  for (auto& n : mesh.normals) n = Vec3(glm::normalize(q * Vec3d(n)));
  for (auto& t : mesh.tangents) t = Vec3(glm::normalize(q * Vec3d(t)));
}

std::size_t vertex_at(const Mesh& mesh, const Vec3d& p) {
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    if (glm::length(Vec3d(mesh.positions[v]) - p) < 1e-6) return v;
  ADD_FAILURE() << "no vertex at the requested position";
  return 0;
}

double angle_between(const Vec3d& a, const Vec3d& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

TransferParams quiet_params(int r = 32, int s_grid = 8, int s = 2) {
  TransferParams p;
  p.cubemap_resolution = r;
  p.local_grid = s_grid;
  p.supersampling = s;
  p.show_progress = false;
  return p;
}

// Sum over the block of point 0 of (T L)_j with L_k = solidAngle_k, in double.
double visible_solid_angle(const TransferMatrix& t, const CubemapLayout& layout,
                           std::size_t point) {
  double sum = 0.0;
  const std::size_t m = static_cast<std::size_t>(t.local_count());
  for (std::size_t row = point * m; row < (point + 1) * m; ++row)
    for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i)
      sum += t.counts()[i] * t.scale() * layout.solid_angle(static_cast<int>(t.column(i)));
  return sum;
}

// The horizon error bound of docs/transfer.md for an unoccluded point with normal n.
// T gives pixel k the weight c_k / s^2 * omega_k, i.e. omega_k / s^2 per sub-ray whose centre
// is above the horizon; the truth is sum_r |subpixel_r cap H|. Pixels wholly above or below
// contribute no error (their sub-pixel weights sum to omega_k). In a straddling pixel, a
// sub-pixel wholly above errs by |omega_k / s^2 - omega_r|, one wholly below by 0, and one
// that straddles by at most max(omega_k / s^2, omega_r).
double horizon_bound(const SupersampledCubemap& dirs, const Vec3d& n) {
  const CubemapLayout layout(dirs.resolution());
  const int ss = dirs.subrays_per_pixel();
  double bound = 0.0;
  for (int k = 0; k < layout.pixel_count(); ++k) {
    double pixel_bound = 0.0;
    bool straddles = false;
    const double share = layout.solid_angle(k) / ss;
    for (int i = 0; i < ss; ++i) {
      const std::size_t r = static_cast<std::size_t>(k) * ss + i;
      int face;
      double s0, s1, t0, t1;
      dirs.subpixel_bounds(r, face, s0, s1, t0, t1);
      int pos = 0;
      for (double cs : {s0, s1})
        for (double ct : {t0, t1})
          pos += glm::dot(CubemapLayout::face_direction(face, cs, ct), n) > 0;
      const double omega = dirs.solid_angles()[r];
      if (pos == 4) {
        pixel_bound += std::abs(share - omega);
      } else if (pos > 0) {
        pixel_bound += std::max(share, omega);
        straddles = true;
      } else {
        straddles = true;
      }
    }
    if (straddles && pixel_bound > 0.0) bound += pixel_bound;
  }
  return bound;
}

TEST(TransferMatrix, OpenPlaneAlignedWithCubeSeesExactlyTwoPi) {
  // Normal +y: the horizon runs along pixel edges, so no pixel straddles it and the sum is
  // exact up to rounding.
  const Mesh plane = make_plane(2.0, 2.0, 2);
  const auto result = compute_transfer(plane, quiet_params());
  const CubemapLayout layout(32);
  const std::size_t v = vertex_at(plane, {0, 0, 0});
  EXPECT_NEAR(visible_solid_angle(result.transfer, layout, v), kTwoPi, 1e-9);
  EXPECT_EQ(result.stats.horizon_lifted, 0u);
}

TEST(TransferMatrix, TiltedOpenPlaneSeesTwoPiWithinTheHorizonBound) {
  Mesh plane = make_plane(2.0, 2.0, 2);
  const Mat3d q = rotation({1.0, 0.2, 0.7}, 0.45);
  transform(plane, q);
  const std::size_t v = vertex_at(plane, {0, 0, 0});
  const Vec3d n = Vec3d(plane.normals[v]);
  const CubemapLayout layout(32);
  double previous_bound = 1e9;
  for (int s : {1, 2, 4}) {
    const auto result = compute_transfer(plane, quiet_params(32, 8, s));
    const double sum = visible_solid_angle(result.transfer, layout, v);
    const double bound = horizon_bound(SupersampledCubemap(32, s), n);
    SCOPED_TRACE(testing::Message()
                 << "s = " << s << ": sum - 2pi = " << sum - kTwoPi << ", bound " << bound);
    EXPECT_LE(std::abs(sum - kTwoPi), bound);
    EXPECT_LT(bound, previous_bound);  // finer supersampling, tighter bound
    EXPECT_LT(bound, 0.1 * kTwoPi);    // and a meaningful one
    // Stronger than the bound: the sub-ray set is antipodally symmetric with equal pixel
    // weights for antipodal pixels, and exactly one ray of each antipodal pair is above any
    // plane through the origin, so the open-plane sum is 2 pi exactly -- provided no unblocked
    // sub-ray is dropped, which is what lifting sub-horizon centres into the rim cells ensures.
    EXPECT_NEAR(sum, kTwoPi, 1e-9);
    RecordProperty("horizon_bound_s" + std::to_string(s), std::to_string(bound));
    if (s > 1) {
      EXPECT_GT(result.stats.horizon_lifted, 0u);
    }
    previous_bound = bound;
  }
}

// Checks every structural invariant of the header on a computed matrix.
void expect_well_formed(const TransferMatrix& t) {
  const int ss = t.supersampling() * t.supersampling();
  ASSERT_EQ(t.row_offsets().size(), t.rows() + 1);
  ASSERT_EQ(t.row_offsets().back(), t.nnz());
  const std::size_t m = static_cast<std::size_t>(t.local_count());
  for (std::size_t v = 0; v < t.vertex_count(); ++v) {
    std::set<std::uint32_t> columns;
    for (std::size_t row = v * m; row < (v + 1) * m; ++row) {
      for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i) {
        ASSERT_TRUE(columns.insert(t.column(i)).second)
            << "vertex " << v << ": column " << t.column(i) << " twice";
        ASSERT_GE(t.counts()[i], 1);
        ASSERT_LE(t.counts()[i], ss);
        ASSERT_LT(t.column(i), t.cols());
        if (i > t.row_offsets()[row]) {
          ASSERT_LT(t.column(i - 1), t.column(i));
        }
        // The value is an exact multiple of 1 / s^2.
        const double x = t.value(i) * ss;
        ASSERT_EQ(x, std::round(x));
      }
    }
  }
}

Mesh plane_and_sphere() {
  Mesh mesh = make_plane(3.0, 3.0, 4);
  Mesh sphere = make_sphere(0.5, 16, 8);
  transform(sphere, Mat3d(1.0), {0.2, 0.8, -0.1});
  mesh.append(sphere, 1);
  return mesh;
}

TEST(TransferMatrix, BlocksHaveOneNonZeroPerColumnAndExactValues) {
  const Mesh mesh = plane_and_sphere();
  for (int s : {2, 3}) {
    const auto result = compute_transfer(mesh, quiet_params(8, 4, s));
    const TransferMatrix& t = result.transfer;
    EXPECT_EQ(t.vertex_count(), mesh.vertex_count());
    EXPECT_EQ(t.rows(), mesh.vertex_count() * 16);
    EXPECT_EQ(t.cols(), 6u * 8 * 8);
    EXPECT_TRUE(t.narrow_columns());
    expect_well_formed(t);
    // Occlusion happens: some values are fractional, and fewer than all upper-hemisphere
    // sub-rays escape.
    EXPECT_TRUE(std::any_of(t.counts().begin(), t.counts().end(),
                            [&](std::uint8_t c) { return c < s * s; }));
    EXPECT_LT(result.stats.rays_unblocked, result.stats.rays_traced);
    EXPECT_EQ(result.stats.subrays, mesh.vertex_count() * 6u * 64 * s * s);
    std::uint64_t count_sum = 0;
    for (std::uint8_t c : t.counts()) count_sum += c;
    EXPECT_EQ(count_sum, result.stats.rays_unblocked);  // every escaped sub-ray is in T once
    EXPECT_EQ(t.memory_bytes(), (t.rows() + 1) * 4 + t.nnz() * 3);
    EXPECT_EQ(t.dense_bytes(), t.rows() * t.cols());
  }
}

TEST(CellLookup, AgreesWithCellOfEverywhere) {
  for (int side : {1, 8, 12}) {
    const HemisphereGrid grid(side);
    const CellLookup lookup(grid);
    if (side > 1) {
      EXPECT_LT(lookup.deferred_fraction(), 0.25) << "S = " << side;
    }
    std::mt19937_64 rng(7 + side);
    std::normal_distribution<double> g;
    for (int i = 0; i < 100000; ++i) {
      Vec3d d{g(rng), g(rng), std::abs(g(rng)) + 1e-12};
      d = glm::normalize(d);
      ASSERT_EQ(lookup.cell_of(d), grid.cell_of(d)) << d.x << " " << d.y << " " << d.z;
    }
    // Directions a hair from cell boundaries: images of the square's grid lines, and the
    // horizon (lifted directions have z = 1e-9).
    for (int line = 0; line <= side; ++line) {
      for (int step = 0; step < 2000; ++step) {
        for (double eps : {-1e-7, 1e-7}) {
          const double a = std::clamp(static_cast<double>(line) / side + eps, 0.0, 1.0);
          const double b = (step + 0.5) / 2000;
          for (const Vec2d ab : {Vec2d(a, b), Vec2d(b, a)}) {
            const Vec3d d = square_to_hemisphere(ab);
            if (!(d.z > 0.0)) continue;
            ASSERT_EQ(lookup.cell_of(d), grid.cell_of(d)) << ab.x << " " << ab.y;
          }
        }
      }
    }
    for (int step = 0; step < 10000; ++step) {
      const double phi = kTwoPi * step / 10000;
      const Vec3d d{std::cos(phi), std::sin(phi), 1e-9};
      ASSERT_EQ(lookup.cell_of(d), grid.cell_of(d)) << phi;
    }
  }
}

// Every entry sits in the row of the local cell containing its pixel's centre direction
// (centres on or below the tangent plane lifted to the rim at their azimuth).
TEST(TransferMatrix, EntriesSitInTheCellContainingThePixelCentre) {
  const Mesh mesh = plane_and_sphere();
  const auto t = compute_transfer(mesh, quiet_params(16, 6, 2)).transfer;
  const CubemapLayout layout(16);
  const HemisphereGrid grid(6);
  std::size_t lifted = 0;
  for (std::size_t row = 0; row < t.rows(); ++row) {
    const std::size_t v = row / 36;
    const LocalFrame frame = mesh.frame(v);
    for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i) {
      Vec3d l = frame.to_local(layout.direction(static_cast<int>(t.column(i))));
      if (l.z <= 0.0) {
        ++lifted;
        l = Vec3d(glm::normalize(Vec2d(l.x, l.y)), 1e-9);
      }
      ASSERT_EQ(static_cast<int>(row % 36), grid.cell_of(l))
          << "vertex " << v << ", pixel " << t.column(i);
    }
  }
  EXPECT_GT(lifted, 0u);  // the sphere's vertices have tilted normals: some centres are lifted
}

TEST(TransferMatrix, DeterministicAcrossThreadCounts) {
  const Mesh mesh = plane_and_sphere();
  TransferParams params = quiet_params(8, 4, 2);
  params.sh_order = 3;
  const auto many = compute_transfer(mesh, params);
  tbb::task_arena one(1);
  TransferResult single;
  one.execute([&] { single = compute_transfer(mesh, params); });
  EXPECT_TRUE(many.transfer == single.transfer);
  ASSERT_TRUE(many.sh && single.sh);
  EXPECT_TRUE(*many.sh == *single.sh);
}

TEST(TransferMatrix, ATracerGivesAnySplitOfThePointsTheRowsOfTheWhole) {
  // What a distributed precompute relies on: one tracer, the points in uneven pieces, and every
  // vertex's rows (and SH matrix) equal to those of the single computation, bit for bit.
  const Mesh mesh = plane_and_sphere();
  TransferParams params = quiet_params(8, 4, 2);
  params.sh_order = 3;
  const auto whole = compute_transfer(mesh, params);
  const auto points = vertex_points(mesh);
  const TransferTracer tracer(mesh, params);
  const int m = whole.transfer.local_count();
  const std::size_t cuts[] = {0, 1, 7, points.size() / 2, points.size()};
  for (std::size_t k = 0; k + 1 < std::size(cuts); ++k) {
    const std::size_t first = cuts[k], count = cuts[k + 1] - cuts[k];
    const auto part = tracer.compute(std::span(points).subspan(first, count));
    ASSERT_EQ(part.transfer.vertex_count(), count);
    for (std::size_t v = 0; v < count; ++v) {
      for (int j = 0; j < m; ++j) {
        const std::size_t a = v * m + j, b = (first + v) * m + j;
        const auto pa = part.transfer.row_offsets(), pb = whole.transfer.row_offsets();
        ASSERT_EQ(pa[a + 1] - pa[a], pb[b + 1] - pb[b]) << "vertex " << first + v;
        for (std::uint32_t e = 0; e < pa[a + 1] - pa[a]; ++e) {
          ASSERT_EQ(part.transfer.column(pa[a] + e), whole.transfer.column(pb[b] + e));
          ASSERT_EQ(part.transfer.counts()[pa[a] + e], whole.transfer.counts()[pb[b] + e]);
        }
      }
      const auto sa = part.sh->matrix(v), sb = whole.sh->matrix(first + v);
      ASSERT_TRUE(std::equal(sa.begin(), sa.end(), sb.begin())) << "SH of vertex " << first + v;
    }
  }
}

TEST(TransferMatrix, OneRankOfADistributedComputationIsTheSingleComputation) {
  // Without mpirun the world is one process: the distributed entry point is compute_transfer,
  // and its data checksum tells results apart.
  const Mesh mesh = plane_and_sphere();
  TransferParams params = quiet_params(8, 4, 2);
  params.sh_order = 2;
  Communicator& world = Communicator::world();
  ASSERT_FALSE(world.distributed());
  const auto d = compute_transfer_distributed(mesh, params, world);
  const auto single = compute_transfer(mesh, params);
  EXPECT_TRUE(d.result.transfer == single.transfer);
  EXPECT_EQ(transfer_data_checksum(d.result), transfer_data_checksum(single));
  ASSERT_EQ(d.shares.size(), 1u);
  EXPECT_EQ(d.shares[0].points, mesh.vertex_count());
  params.supersampling = 3;  // another T: another checksum
  EXPECT_NE(transfer_data_checksum(compute_transfer(mesh, params)), transfer_data_checksum(single));
}

TEST(TransferMatrix, FromCsrRoundTripsAndRejectsBrokenArrays) {
  const Mesh mesh = plane_and_sphere();
  const TransferMatrix t = compute_transfer(mesh, quiet_params(8, 4, 2)).transfer;
  std::vector<std::uint32_t> offsets(t.row_offsets().begin(), t.row_offsets().end());
  std::vector<std::uint32_t> cols(t.nnz());
  for (std::size_t i = 0; i < t.nnz(); ++i) cols[i] = t.column(i);
  std::vector<std::uint8_t> counts(t.counts().begin(), t.counts().end());
  const auto rebuilt = TransferMatrix::from_csr(
      t.vertex_count(), t.local_count(), static_cast<int>(t.cols()), 2, offsets, cols, counts);
  EXPECT_TRUE(rebuilt == t);
  // at() finds stored entries and returns 0 elsewhere.
  std::size_t checked = 0;
  for (std::size_t row = 0; row < t.rows() && checked < 50; ++row) {
    for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i, ++checked) {
      EXPECT_DOUBLE_EQ(rebuilt.at(row, cols[i]), counts[i] / 4.0);
      if (i + 1 < t.row_offsets()[row + 1] && cols[i] + 1 < cols[i + 1]) {
        EXPECT_EQ(rebuilt.at(row, cols[i] + 1), 0.0);
      }
    }
  }
  EXPECT_GT(checked, 0u);

  auto expect_rejected = [&](auto mutate) {
    auto o = offsets;
    auto c = cols;
    auto n = counts;
    mutate(o, c, n);
    EXPECT_THROW(TransferMatrix::from_csr(t.vertex_count(), t.local_count(),
                                          static_cast<int>(t.cols()), 2, o, c, n),
                 ParameterError);
  };
  expect_rejected([](auto&, auto&, auto& n) { n[5] = 5; });        // count above s^2
  expect_rejected([](auto&, auto&, auto& n) { n[5] = 0; });        // stored zero
  expect_rejected([&](auto&, auto& c, auto&) { c[0] = 6 * 64; });  // column out of range
  expect_rejected([](auto& o, auto&, auto&) { o.pop_back(); });    // missing offset
  expect_rejected([](auto& o, auto&, auto&) { o.back() -= 1; });   // offsets do not end at nnz

  // One vertex, M = 2, N = 4: the same column in both rows of a block is not a transfer block,
  // while the same column in two different vertices' blocks is fine.
  const std::vector<std::uint32_t> two_rows{0, 1, 2};
  EXPECT_THROW(
      TransferMatrix::from_csr(1, 2, 4, 2, two_rows, std::vector<std::uint32_t>{3, 3}, {1, 1}),
      ParameterError);
  EXPECT_NO_THROW(
      TransferMatrix::from_csr(1, 2, 4, 2, two_rows, std::vector<std::uint32_t>{3, 2}, {1, 1}));
  EXPECT_NO_THROW(
      TransferMatrix::from_csr(2, 1, 4, 2, two_rows, std::vector<std::uint32_t>{3, 3}, {1, 4}));
  // Wide cubemaps switch to 32-bit column indices.
  const auto wide =
      TransferMatrix::from_csr(1, 1, 70000, 1, {0, 1}, std::vector<std::uint32_t>{69999}, {1});
  EXPECT_FALSE(wide.narrow_columns());
  EXPECT_EQ(wide.column(0), 69999u);
}

// Rotating the mesh and the environment together: L'(d) = L(Q^-1 d). The local radiance per
// cell must not change beyond the discretisation error. Both configurations approximate the
// same integral I_j of V L over cell j; each differs from it by at most
//   sum over pixels k "uncertain" for cell j of |L_k|  (+ the smoothness term below)
// where k is uncertain when its footprint is not wholly inside one cell (sampled on a 5 x 5
// grid of the pixel, the horizon counting as a cell of its own) or when it comes within its
// angular radius of the sphere's shadow cone (whose rim the polygonal sphere may move by the
// tessellation's sagitta). The smoothness term covers the point-sampled light: over the pixel,
// |L(d) - L(d_k)| <= (largest deviation at the 5 x 5 samples) + G radius_k / 4, with G a bound
// of |grad L| on the sphere.
struct Config {
  Mat3d q;
  Mesh mesh;
  SurfacePoint point;
};

// A smooth sky with a broad bright lobe: low frequency, but far from constant, so an
// unrotated light or a permuted cell changes L* well beyond the bound.
Vec3d light_fn(const Vec3d& d) {
  const Vec3d lobe = glm::normalize(Vec3d(-0.5, 0.6, 0.4));
  return (0.3 + 1.5 * std::exp(3.0 * (glm::dot(d, lobe) - 1.0))) * Vec3d(1.0, 0.9, 0.8);
}
// |grad L| <= 1.5 * 3 * |(1, 0.9, 0.8)| = 6.97 (the lobe's tangential gradient is at most
// 3 e^{3(c-1)} sqrt(1 - c^2) <= 3).
constexpr double kLightGradient = 7.0;

struct Uncertainty {
  std::vector<double> per_cell;
  double total = 0.0;  ///< for the sum over all cells: horizon and shadow rim only
};

Uncertainty uncertainty(const Config& c, const CubemapLayout& layout, const HemisphereGrid& grid,
                        const std::vector<Rgb>& light, const Vec3d& sphere_centre, double rho,
                        double rho_in, double offset) {
  const int r = layout.resolution();
  Uncertainty u;
  u.per_cell.assign(static_cast<std::size_t>(grid.cell_count()), 0.0);
  const Vec3d origin = c.point.position + offset * c.point.frame.n;
  const Vec3d centre = c.q * sphere_centre;
  const Vec3d axis = glm::normalize(centre - origin);
  const double dist = glm::length(centre - origin);
  const double alpha_out = std::asin(rho / dist), alpha_in = std::asin(rho_in / dist);
  for (int k = 0; k < layout.pixel_count(); ++k) {
    const int face = k / (r * r), x = (k % (r * r)) % r, y = (k % (r * r)) / r;
    auto sample = [&](int i, int j) {
      return CubemapLayout::face_direction(face, 2.0 * (x + i / 4.0) / r - 1.0,
                                           2.0 * (y + j / 4.0) / r - 1.0);
    };
    // The pixel is the convex hull of its corners: its angular radius is the largest corner
    // angle, and it is wholly below the horizon when all corners are.
    double radius = 0.0;
    bool below = true;
    for (int i : {0, 4})
      for (int j : {0, 4}) {
        radius = std::max(radius, angle_between(sample(i, j), layout.direction(k)));
        below = below && glm::dot(sample(i, j), c.point.frame.n) <= 0.0;
      }
    if (below) continue;
    std::set<int> cells;
    const Vec3d centre_light = light_fn(glm::transpose(c.q) * layout.direction(k));
    double deviation = 0.0;
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; j <= 4; ++j) {
        cells.insert(grid.cell_of(c.point.frame.to_local(sample(i, j))));
        deviation = std::max(
            deviation, glm::length(light_fn(glm::transpose(c.q) * sample(i, j)) - centre_light));
      }
    const double mag = glm::length(Vec3d(light[k]));
    // Every point of the pixel is within radius / 4 (half the diagonal of a sample spacing,
    // with margin for the gnomonic skew) of a sample, so the light deviates from its centre
    // value by at most this.
    const double smooth = (deviation + kLightGradient * radius / 4.0) * layout.solid_angle(k);
    const double a = angle_between(layout.direction(k), axis);
    const bool near_cone = a > alpha_in - radius - 1e-3 && a < alpha_out + radius + 1e-3;
    const bool uncertain = cells.size() > 1 || near_cone;
    for (int j : cells) {
      if (j < 0) continue;
      u.per_cell[j] += smooth + (uncertain ? mag : 0.0);
    }
    u.total += smooth + (near_cone || cells.count(-1) ? mag : 0.0);
  }
  return u;
}

TEST(TransferMatrix, RotatingSceneAndLightTogetherLeavesLocalRadianceUnchanged) {
  const Vec3d sphere_centre{0.35, 0.9, -0.2};
  const double rho = 0.45;
  const int segments = 96, rings = 48;
  Mesh base = make_plane(4.0, 4.0, 2);
  Mesh sphere = make_sphere(rho, segments, rings);
  transform(sphere, Mat3d(1.0), sphere_centre);
  base.append(sphere, 1);
  const double rho_in = rho * std::cos(std::hypot(kTwoPi / segments, kPi / rings));
  const std::size_t v = vertex_at(base, {0, 0, 0});

  // R = 128: a local cell is then about 28 pixels wide, so the pixels on cell boundaries are a
  // small part of each cell and the per-cell bound is far below the cell's value.
  const int r = 128;
  const CubemapLayout layout(r);
  const HemisphereGrid grid(8);
  const auto params = quiet_params(r, 8, 2);

  std::vector<Config> configs;
  for (const Mat3d& q : {Mat3d(1.0), rotation({0.3, -1.0, 0.6}, 1.1)}) {
    Config c{q, base, {}};
    transform(c.mesh, q);
    c.point.position = Vec3d(c.mesh.positions[v]);
    c.point.frame = c.mesh.frame(v);
    configs.push_back(std::move(c));
  }

  std::vector<std::vector<double>> lstar;
  std::vector<Uncertainty> bounds;
  for (const Config& c : configs) {
    std::vector<Rgb> light(layout.pixel_count());
    for (int k = 0; k < layout.pixel_count(); ++k)
      light[k] = Rgb(light_fn(glm::transpose(c.q) * layout.direction(k)) * layout.solid_angle(k));
    const SurfacePoint pts[] = {c.point};
    const TransferMatrix t = compute_transfer(c.mesh, pts, params).transfer;
    std::vector<double> out(grid.cell_count(), 0.0);  // one channel sum is enough: all positive
    for (std::size_t row = 0; row < t.rows(); ++row)
      for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i) {
        const Rgb& l = light[t.column(i)];
        out[row] += t.counts()[i] * t.scale() * glm::length(Vec3d(l));
      }
    lstar.push_back(out);
    bounds.push_back(uncertainty(c, layout, grid, light, sphere_centre, rho, rho_in,
                                 EmbreeScene(c.mesh).ray_offset()));
  }

  double total0 = 0, total1 = 0, max_rel_diff = 0;
  int shadowed = 0;
  std::vector<double> bound_fraction;
  for (int j = 0; j < grid.cell_count(); ++j) {
    const double diff = std::abs(lstar[0][j] - lstar[1][j]);
    const double bound = bounds[0].per_cell[j] + bounds[1].per_cell[j];
    EXPECT_LE(diff, bound) << "cell " << j << ": " << lstar[0][j] << " vs " << lstar[1][j];
    total0 += lstar[0][j];
    total1 += lstar[1][j];
    max_rel_diff = std::max(max_rel_diff, diff / std::max(lstar[0][j], 1e-9));
    // Whole cells in the sphere's shadow: a permutation of cells would show.
    if (lstar[0][j] < 0.01 * grid.cell_solid_angle()) {
      ++shadowed;
    } else {
      bound_fraction.push_back(bound / lstar[0][j]);
    }
  }
  EXPECT_GT(shadowed, 0);
  // The bound counts every pixel on a cell boundary in full (the pixel goes wholly to the cell
  // of its centre), about a fifth of a cell per configuration at R = 128, S = 8: loose, but a
  // typical cell's bound is still well under its value.
  std::sort(bound_fraction.begin(), bound_fraction.end());
  const double median_bound_fraction = bound_fraction[bound_fraction.size() / 2];
  EXPECT_LT(median_bound_fraction, 0.6);
  // Totals have no cell-boundary error; only the shadow rim and the horizon remain.
  EXPECT_NEAR(total0, total1, bounds[0].total + bounds[1].total);
  EXPECT_LT(bounds[0].total + bounds[1].total, 0.1 * total0);
  RecordProperty("max_relative_cell_difference", std::to_string(max_rel_diff));
  RecordProperty("median_bound_fraction", std::to_string(median_bound_fraction));
  RecordProperty("total_difference", std::to_string(std::abs(total0 - total1)));
  RecordProperty("total_bound", std::to_string(bounds[0].total + bounds[1].total));
}

TEST(TransferMatrix, RejectsMeshWithoutNormals) {
  Mesh mesh = make_plane(1.0, 1.0, 1);
  Mesh degenerate = mesh;
  mesh.normals.clear();
  EXPECT_THROW(compute_transfer(mesh, quiet_params()), ParameterError);
  degenerate.normals[1] = Vec3(0.f);
  EXPECT_THROW(compute_transfer(degenerate, quiet_params()), ParameterError);
}

}  // namespace
}  // namespace prt
