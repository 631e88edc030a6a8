#pragma once
// The transfer of a sphere floating over a plane, the synthetic scene of the conformance
// suite, the Python reader's fixtures and the fuzzers' seeds: every backend, the SH ones
// included, compresses it at default parameters in seconds.
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::testing {

/// `plane_n` x `plane_n` plane cells and a sphere of `segments` x `segments / 2`: 4 and 12
/// for the suites, smaller for seeds that must stay a few KB.
inline TransferResult sphere_over_plane_transfer(int sh_order = 0, int plane_n = 4,
                                                 int segments = 12) {
  Mesh mesh = make_plane(3.0, 3.0, plane_n);
  Mesh sphere = make_sphere(0.5, segments, segments / 2);
  for (auto& p : sphere.positions) p += Vec3(0.2f, 0.8f, -0.1f);
  mesh.append(sphere, 1);
  TransferParams params;
  params.cubemap_resolution = 8;
  params.local_grid = 4;
  params.supersampling = 2;
  params.sh_order = sh_order;
  params.show_progress = false;
  return compute_transfer(mesh, params);
}

}  // namespace prt::testing
