#include "prtlab/geometry/procedural_shapes.h"

#include <cmath>
#include <string_view>
#include <vector>

#include "prtlab/base/error.h"

namespace prt {
namespace {

struct GridVertex {
  Vec3d p, n, t;
};

void require_positive(double value, std::string_view what) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw ParameterError(
        fmt::format("procedural shape: {} must be positive and finite, not {}", what, value));
}
void require_count(int value, int minimum, std::string_view what) {
  if (value < minimum || value > 1 << 14)
    throw ParameterError(fmt::format("procedural shape: {} must be in [{}, {}], not {}", what,
                                     minimum, 1 << 14, value));
}

/// Appends a (cols+1) x (rows+1) vertex grid with uv = (i/cols, j/rows), two triangles per
/// cell wound so that d/du x d/dv faces the front. Triangles with two equal positions (at a
/// pole) are skipped.
template <typename F>
void add_grid(Mesh& mesh, int cols, int rows, F&& vertex_at) {
  const auto base = static_cast<std::uint32_t>(mesh.positions.size());
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i <= cols; ++i) {
      const GridVertex g = vertex_at(i, j);
      mesh.positions.emplace_back(g.p);
      mesh.normals.emplace_back(g.n);
      mesh.tangents.emplace_back(g.t);
      mesh.uvs.emplace_back(static_cast<float>(i) / static_cast<float>(cols),
                            static_cast<float>(j) / static_cast<float>(rows));
    }
  }
  const auto at = [&](int i, int j) {
    return base + static_cast<std::uint32_t>(j * (cols + 1) + i);
  };
  const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    const Vec3& pa = mesh.positions[a];
    const Vec3& pb = mesh.positions[b];
    const Vec3& pc = mesh.positions[c];
    if (pa == pb || pb == pc || pa == pc) return;
    mesh.indices.insert(mesh.indices.end(), {a, b, c});
  };
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      add(at(i, j), at(i + 1, j), at(i, j + 1));
      add(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
}

/// Drops vertices no triangle uses (pole copies whose triangles were skipped).
void remove_unused_vertices(Mesh& mesh) {
  std::vector<std::uint32_t> remap(mesh.vertex_count(), 0);
  for (std::uint32_t i : mesh.indices) remap[i] = 1;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < remap.size(); ++v) {
    if (!remap[v]) continue;
    remap[v] = next;
    mesh.positions[next] = mesh.positions[v];
    mesh.normals[next] = mesh.normals[v];
    mesh.tangents[next] = mesh.tangents[v];
    mesh.uvs[next] = mesh.uvs[v];
    ++next;
  }
  for (std::uint32_t& i : mesh.indices) i = remap[i];
  mesh.positions.resize(next);
  mesh.normals.resize(next);
  mesh.tangents.resize(next);
  mesh.uvs.resize(next);
}

/// cos and sin of 2 pi k / n, with k taken modulo n so that a seam repeats bit-identical values.
std::pair<double, double> around(int k, int n) {
  const double a = kTwoPi * static_cast<double>(k % n) / static_cast<double>(n);
  return {std::cos(a), std::sin(a)};
}

/// Grid parameter (2k - n) / n in [-1, 1]: exact under negation, so that box faces meeting
/// at an edge produce identical coordinates whichever way their axes run.
double signed_param(int k, int n) {
  return static_cast<double>(2 * k - n) / static_cast<double>(n);
}

}  // namespace

Mesh make_sphere(double radius, int segments, int rings) {
  require_positive(radius, "sphere radius");
  require_count(segments, 3, "sphere segments");
  require_count(rings, 2, "sphere rings");
  Mesh mesh;
  add_grid(mesh, segments, rings, [&](int i, int j) {
    const auto [cp, sp] = around(i, segments);
    // theta from the north pole; exact poles so that their vertices coincide.
    double st = 0.0, ct = j == 0 ? -1.0 : 1.0;
    if (j != 0 && j != rings) {
      const double theta = kPi * (1.0 - static_cast<double>(j) / static_cast<double>(rings));
      st = std::sin(theta);
      ct = std::cos(theta);
    }
    const Vec3d n(st * cp, ct, -st * sp);
    return GridVertex{radius * n, n, Vec3d(-sp, 0.0, -cp)};
  });
  remove_unused_vertices(mesh);
  return mesh;
}

Mesh make_plane(double size_x, double size_z, int n) {
  require_positive(size_x, "plane size_x");
  require_positive(size_z, "plane size_z");
  require_count(n, 1, "plane subdivisions");
  Mesh mesh;
  add_grid(mesh, n, n, [&](int i, int j) {
    return GridVertex{
        Vec3d(0.5 * size_x * signed_param(i, n), 0.0, -0.5 * size_z * signed_param(j, n)),
        Vec3d(0, 1, 0), Vec3d(1, 0, 0)};
  });
  return mesh;
}

Mesh make_box(const Vec3d& half_extent, int n) {
  require_positive(half_extent.x, "box half extent x");
  require_positive(half_extent.y, "box half extent y");
  require_positive(half_extent.z, "box half extent z");
  require_count(n, 1, "box subdivisions");
  // Each face: outward normal N, u axis U, v axis V = N x U (right-handed UVs).
  struct Face {
    Vec3d n, u;
  };
  static constexpr Face kFaces[6] = {
      {{1, 0, 0}, {0, 0, -1}}, {{-1, 0, 0}, {0, 0, 1}}, {{0, 1, 0}, {1, 0, 0}},
      {{0, -1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 0}},  {{0, 0, -1}, {-1, 0, 0}},
  };
  Mesh mesh;
  for (const Face& f : kFaces) {
    const Vec3d v = glm::cross(f.n, f.u);
    // Component-wise products keep every coordinate a single exact term (no sums).
    const Vec3d hn = f.n * half_extent, hu = f.u * half_extent, hv = v * half_extent;
    add_grid(mesh, n, n, [&](int i, int j) {
      return GridVertex{hn + hu * signed_param(i, n) + hv * signed_param(j, n), f.n, f.u};
    });
  }
  return mesh;
}

Mesh make_torus(double major_radius, double minor_radius, int segments, int sides) {
  require_positive(minor_radius, "torus minor radius");
  if (!(major_radius > minor_radius) || !std::isfinite(major_radius))
    throw ParameterError(
        fmt::format("procedural shape: torus major radius {} must exceed the minor radius {}",
                    major_radius, minor_radius));
  require_count(segments, 3, "torus segments");
  require_count(sides, 3, "torus sides");
  Mesh mesh;
  add_grid(mesh, segments, sides, [&](int i, int j) {
    const auto [cp, sp] = around(i, segments);
    const auto [cs, ss] = around(j, sides);
    const double ring = major_radius + minor_radius * cs;
    return GridVertex{Vec3d(ring * cp, minor_radius * ss, -ring * sp), Vec3d(cs * cp, ss, -cs * sp),
                      Vec3d(-sp, 0.0, -cp)};
  });
  return mesh;
}

Mesh make_cylinder(double radius, double height, int segments, int rings) {
  require_positive(radius, "cylinder radius");
  require_positive(height, "cylinder height");
  require_count(segments, 3, "cylinder segments");
  require_count(rings, 1, "cylinder rings");
  Mesh mesh;
  const auto rim = [&](int i, double y) {
    const auto [c, s] = around(i, segments);
    return Vec3d(radius * c, y, -radius * s);
  };
  add_grid(mesh, segments, rings, [&](int i, int j) {
    const auto [c, s] = around(i, segments);
    const double y =
        j == rings ? height : height * static_cast<double>(j) / static_cast<double>(rings);
    return GridVertex{rim(i, y), Vec3d(c, 0.0, -s), Vec3d(-s, 0.0, -c)};
  });
  // Caps: a centre and a ring, planar UVs with u along +x and v along n x (+x).
  for (const bool top : {false, true}) {
    const double y = top ? height : 0.0;
    const Vec3 n(0.f, top ? 1.f : -1.f, 0.f);
    const float v_sign = top ? -1.f : 1.f;
    const auto centre = static_cast<std::uint32_t>(mesh.positions.size());
    const auto push = [&](const Vec3d& p) {
      mesh.positions.emplace_back(p);
      mesh.normals.push_back(n);
      mesh.tangents.emplace_back(1.f, 0.f, 0.f);
      mesh.uvs.emplace_back(0.5f + static_cast<float>(p.x / (2.0 * radius)),
                            0.5f + v_sign * static_cast<float>(p.z / (2.0 * radius)));
    };
    push(Vec3d(0.0, y, 0.0));
    for (int i = 0; i < segments; ++i) push(rim(i, y));
    for (int i = 0; i < segments; ++i) {
      const std::uint32_t a = centre + 1 + static_cast<std::uint32_t>(i);
      const std::uint32_t b = centre + 1 + static_cast<std::uint32_t>((i + 1) % segments);
      if (top)
        mesh.indices.insert(mesh.indices.end(), {centre, a, b});
      else
        mesh.indices.insert(mesh.indices.end(), {centre, b, a});
    }
  }
  return mesh;
}

}  // namespace prt
