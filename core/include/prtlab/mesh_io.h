#pragma once
// Mesh loading through assimp (OFF, PLY, OBJ and everything else assimp reads), with
// validation. Problems are reported with the file name and the first offending element:
//   - missing or unreadable file, a format assimp cannot parse, a truncated file
//   - an empty mesh (no vertices or no triangles)
//   - NaN or Inf coordinates                                    (error)
//   - indices out of range                                      (error)
//   - degenerate triangles (repeated index or zero area)        (dropped, one warning with a count)
// All meshes in a file are merged into one; unused vertices are removed.
#include <filesystem>

#include "prtlab/mesh.h"

namespace prt {

struct MeshLoadReport {
  std::size_t degenerate_dropped = 0;
  std::size_t unused_vertices_removed = 0;
};

Mesh load_mesh(const std::filesystem::path& file, MeshLoadReport* report = nullptr);

/// Validate an in-memory mesh with the same rules; `source` names it in messages.
void validate_mesh(Mesh& mesh, const std::filesystem::path& source, MeshLoadReport* report = nullptr);

/// Write a mesh as OBJ (for inspection and tests).
void save_mesh_obj(const Mesh& mesh, const std::filesystem::path& file);

}  // namespace prt
