#pragma once
// Procedural meshes for tests and composed scenes. All have UVs, normals and tangents.
#include "prtlab/mesh.h"

namespace prt {

/// UV sphere of radius r centred at the origin: `segments` around, `rings` pole to pole.
Mesh make_sphere(double radius, int segments, int rings);
/// Plane y = 0, size_x by size_z centred at the origin, facing +y, n x n quads.
Mesh make_plane(double size_x, double size_z, int n);
/// Axis-aligned box centred at the origin with half extents h, each face n x n quads
/// (faces do not share vertices, so normals stay flat).
Mesh make_box(const Vec3d& half_extent, int n);
/// Torus around the y axis: major radius R, minor radius r.
Mesh make_torus(double major_radius, double minor_radius, int segments, int sides);
/// Cylinder along y from 0 to height, radius r, with caps.
Mesh make_cylinder(double radius, double height, int segments, int rings);

}  // namespace prt
