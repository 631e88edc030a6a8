#pragma once
// Procedural meshes for tests and composed scenes. All have UVs, normals and tangents
// (analytic, unit, tangent orthogonal to the normal), counter-clockwise triangles seen from
// outside, and right-handed UVs (cross(normal, tangent) points along +v). Vertices on a UV
// seam or a pole are duplicated with bit-identical positions, so weld_vertices(kPosition)
// closes the closed shapes exactly. Invalid sizes or counts throw ParameterError.
#include "prtlab/geometry/mesh.h"

namespace prt {

/// UV sphere of radius r centred at the origin: `segments` around (>= 3), `rings` pole to
/// pole (>= 2). u runs around y, v from the south pole (0) to the north pole (1).
/// (segments + 1) x (rings - 1) + 2 segments vertices: each pole has one copy per segment.
Mesh make_sphere(double radius, int segments, int rings);
/// Plane y = 0, size_x by size_z centred at the origin, facing +y, n x n quads; u along +x,
/// v along -z.
Mesh make_plane(double size_x, double size_z, int n);
/// Axis-aligned box centred at the origin with half extents h, each face n x n quads
/// (faces do not share vertices, so normals stay flat); every face has its own [0,1]^2 UVs.
Mesh make_box(const Vec3d& half_extent, int n);
/// Torus around the y axis: major radius R, minor radius r (R > r > 0); `segments` around
/// y (u), `sides` around the tube (v).
Mesh make_torus(double major_radius, double minor_radius, int segments, int sides);
/// Cylinder along y from 0 to height, radius r, with caps: `segments` around y, `rings`
/// along y. Caps are fans with planar UVs and their own (flat-normal) vertices.
Mesh make_cylinder(double radius, double height, int segments, int rings);

}  // namespace prt
