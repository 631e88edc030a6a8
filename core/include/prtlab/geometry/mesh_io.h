#pragma once
// Mesh loading (OFF by prtlab's own strict reader; PLY, OBJ and everything else assimp reads
// through assimp), with validation. Problems are InputErrors naming the file and the first
// offending element (element indices are 0-based; text formats also give the line):
//   - missing or unreadable file, a format assimp cannot parse (assimp's message is quoted)
//   - a truncated OFF file (header counts against what the file holds)
//   - an empty mesh (no vertices or no triangles)
//   - NaN or Inf coordinates                                    (error)
//   - indices out of range                                      (error)
//   - degenerate triangles (repeated index or zero area)        (dropped, one warning with a count)
// All meshes in a file are merged into one (node transforms applied); unused vertices are
// removed; UVs come from the first texture channel where present. Normals in the file are
// not used: the loaded mesh gets smooth normals and tangents (mesh.h).
#include <filesystem>
#include <string>
#include <vector>

#include "prtlab/geometry/mesh.h"

namespace prt {

struct MeshLoadReport {
  std::size_t degenerate_dropped = 0;
  std::size_t first_degenerate = 0;  ///< index of the first dropped triangle (when any)
  std::size_t unused_vertices_removed = 0;
};

Mesh load_mesh(const std::filesystem::path& file, MeshLoadReport* report = nullptr);

/// What names a group of triangles in a mesh file: the material (OBJ `usemtl`) or the object
/// (OBJ `o` / `g`; assimp's node of the mesh).
enum class MeshGroupKey { kMaterial, kObject };

struct GroupedMesh {
  Mesh mesh;                        ///< triangle_part[t]: index of triangle t's group in `groups`
  std::vector<std::string> groups;  ///< distinct names, in the order the file first uses them
};

/// load_mesh, keeping which group every triangle came from (for scene parts that split one
/// file by material or object). Pieces with the same name form one group; a piece without a
/// name is called "(unnamed)". InputError for an OFF file (it has no groups) and for more
/// than 65,536 groups.
GroupedMesh load_mesh_groups(const std::filesystem::path& file, MeshGroupKey key,
                             MeshLoadReport* report = nullptr);

/// Validate an in-memory mesh with the same rules (drops degenerate triangles with one
/// warning, removes unused vertices); `source` names it in messages.
void validate_mesh(Mesh& mesh, const std::filesystem::path& source,
                   MeshLoadReport* report = nullptr);

/// Write a mesh as OBJ (for inspection and tests): positions, UVs and normals where present, as
/// the shortest decimals that a correctly rounded reader turns back into the same floats.
void save_mesh_obj(const Mesh& mesh, const std::filesystem::path& file);

}  // namespace prt
