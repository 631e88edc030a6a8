#include "prtlab/geometry/mesh_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/storage/atomic_file.h"

namespace prt {
namespace fs = std::filesystem;
namespace {

std::string read_whole_file(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(file, "file not found");
  if (fs::is_directory(file, ec)) throw InputError(file, "is a directory, not a mesh file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "file cannot be opened for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(file, "read error");
  return std::move(ss).str();
}

std::string lower_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// A token quoted in a message: printable, short.
std::string quote(std::string_view token) {
  std::string out;
  for (char c : token.substr(0, 24)) out += (c >= 32 && c < 127) ? c : '?';
  if (token.size() > 24) out += "...";
  return "'" + out + "'";
}

// ---- Line-oriented tokenizer for the text formats -------------------------------------------

struct Line {
  std::size_t number = 0;  ///< 1-based line number in the file
  std::vector<std::string_view> tokens;
};

/// Yields the non-empty lines of a text, comments ('#' to the end of the line) removed.
/// With `continuations`, a line ending in a backslash continues on the next (OBJ).
class LineReader {
 public:
  LineReader(std::string_view text, bool continuations)
      : text_(text), continuations_(continuations) {}

  bool next(Line& line) {
    line.tokens.clear();
    while (pos_ < text_.size()) {
      line.number = line_number_ + 1;
      bool more = true;
      while (more && pos_ < text_.size()) {
        std::size_t end = text_.find('\n', pos_);
        if (end == std::string_view::npos) end = text_.size();
        std::string_view raw = text_.substr(pos_, end - pos_);
        pos_ = end + 1;
        ++line_number_;
        if (const std::size_t hash = raw.find('#'); hash != std::string_view::npos)
          raw = raw.substr(0, hash);
        while (!raw.empty() && is_space(raw.back())) raw.remove_suffix(1);
        more = continuations_ && !raw.empty() && raw.back() == '\\';
        if (more) raw.remove_suffix(1);
        split(raw, line.tokens);
      }
      if (!line.tokens.empty()) return true;
    }
    return false;
  }
  bool at_end() const { return pos_ >= text_.size(); }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
  }
  static void split(std::string_view s, std::vector<std::string_view>& out) {
    std::size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && is_space(s[i])) ++i;
      const std::size_t start = i;
      while (i < s.size() && !is_space(s[i])) ++i;
      if (i > start) out.push_back(s.substr(start, i - start));
    }
  }

  std::string_view text_;
  bool continuations_;
  std::size_t pos_ = 0;
  std::size_t line_number_ = 0;
};

std::optional<double> parse_double(std::string_view token) {
  double v = 0.0;
  const char* first = token.data();
  if (!token.empty() && token.front() == '+') ++first;  // from_chars rejects a leading '+'
  const auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), v);
  // Out-of-range values parse as +-inf so that they are reported as infinite coordinates.
  if (ec == std::errc::result_out_of_range)
    return first < ptr && *first == '-' ? -HUGE_VAL : HUGE_VAL;
  if (ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
  return v;
}

std::optional<std::int64_t> parse_int(std::string_view token) {
  std::int64_t v = 0;
  const char* first = token.data();
  if (!token.empty() && token.front() == '+') ++first;
  const auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), v);
  if (ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
  return v;
}

/// "has a NaN coordinate" / "has an infinite coordinate" / "" when the values are finite
/// (as floats: a double beyond float range would become inf in the mesh).
std::string non_finite_problem(std::initializer_list<double> values, const char* what) {
  for (double v : values)
    if (std::isnan(v)) return fmt::format("has a NaN {}", what);
  for (double v : values)
    if (!std::isfinite(static_cast<float>(v))) return fmt::format("has an infinite {}", what);
  return {};
}

// ---- OFF ------------------------------------------------------------------------------------
// OFF is read here, not by assimp: assimp 5.2's OFF reader clamps out-of-range indices to the
// last vertex, silently drops faces with more than 9 vertices, and trips an assertion (abort)
// on a truncated file. Validating all of that needs a full parse anyway.

Mesh read_off(const fs::path& file, std::string_view text) {
  LineReader reader(text, /*continuations=*/false);
  Line line;
  if (!reader.next(line)) throw InputError(file, "empty mesh: the file holds no data");

  // Keyword: [ST][C][N][4]OFF (Geomview); nOFF (other dimensions) is not supported.
  std::string_view key = line.tokens[0];
  // Colours (C) may follow the coordinates in any count; they are skipped.
  const auto take = [&key](std::string_view prefix) {
    if (!key.starts_with(prefix)) return false;
    key.remove_prefix(prefix.size());
    return true;
  };
  const bool has_uv = take("ST");
  take("C");
  const bool has_normal = take("N");
  const bool homogeneous = take("4");
  if (key.starts_with("n"))
    throw InputError(file, "nOFF (vertices of arbitrary dimension) is not supported");
  if (key != "OFF")
    throw InputError(file, fmt::format("not an OFF file: it starts with {} instead of 'OFF'",
                                       quote(line.tokens[0])));

  std::vector<std::string_view> counts(line.tokens.begin() + 1, line.tokens.end());
  std::size_t header_line = line.number;
  if (counts.empty()) {
    if (!reader.next(line))
      throw InputError(file, "truncated: the file ends after the 'OFF' keyword, before the counts");
    counts = line.tokens;
    header_line = line.number;
  }
  const auto nv = counts.size() >= 1 ? parse_int(counts[0]) : std::nullopt;
  const auto nf = counts.size() >= 2 ? parse_int(counts[1]) : std::nullopt;
  if (!nv || !nf || *nv < 0 || *nf < 0)
    throw InputError(
        file, fmt::format("line {}: expected the vertex and face counts after 'OFF'", header_line));
  constexpr std::int64_t kMaxCount = std::numeric_limits<std::uint32_t>::max();
  if (*nv > kMaxCount || *nf > kMaxCount)
    throw InputError(file, fmt::format("line {}: counts {} and {} are beyond 32-bit indices",
                                       header_line, *nv, *nf));
  const auto V = static_cast<std::size_t>(*nv);
  const auto F = static_cast<std::size_t>(*nf);
  if (V == 0) throw InputError(file, "empty mesh: the header declares 0 vertices");
  if (F == 0) throw InputError(file, "empty mesh: the header declares 0 faces");
  const auto truncated = [&](std::string_view where) {
    return InputError(file, fmt::format("truncated: header declares {} vertices and {} faces but "
                                        "the file ends {}",
                                        V, F, where));
  };

  Mesh mesh;
  const std::size_t ncoords = homogeneous ? 4 : 3;
  const std::size_t nvalues = ncoords + (has_normal ? 3 : 0) + (has_uv ? 2 : 0);
  // The counts are not trusted with memory: a 20-byte file may declare four billion vertices
  // and only fail as truncated once read. A vertex line takes at least two bytes per value and
  // a face line four, so the file's size bounds what can really be there.
  const std::size_t vertex_room = std::min(V, text.size() / (2 * nvalues) + 1);
  mesh.positions.reserve(vertex_room);
  if (has_uv) mesh.uvs.reserve(vertex_room);
  for (std::size_t i = 0; i < V; ++i) {
    if (!reader.next(line))
      throw truncated(fmt::format("after {} vert{}", i, i == 1 ? "ex" : "ices"));
    if (line.tokens.size() < nvalues) {
      if (reader.at_end())
        throw truncated(fmt::format("inside vertex {} (line {})", i, line.number));
      throw InputError(file, fmt::format("vertex {} (line {}) has {} values, expected at least {}",
                                         i, line.number, line.tokens.size(), nvalues));
    }
    double c[4] = {0, 0, 0, 1};
    for (std::size_t k = 0; k < ncoords; ++k) {
      const auto value = parse_double(line.tokens[k]);
      if (!value)
        throw InputError(file, fmt::format("vertex {} (line {}): {} is not a number", i,
                                           line.number, quote(line.tokens[k])));
      c[k] = *value;
    }
    if (homogeneous) {
      if (c[3] == 0.0)
        throw InputError(file,
                         fmt::format("vertex {} (line {}) has homogeneous w = 0", i, line.number));
      for (int k = 0; k < 3; ++k) c[k] /= c[3];
    }
    if (const std::string problem = non_finite_problem({c[0], c[1], c[2]}, "coordinate");
        !problem.empty())
      throw InputError(file, fmt::format("vertex {} (line {}) {}", i, line.number, problem));
    mesh.positions.emplace_back(static_cast<float>(c[0]), static_cast<float>(c[1]),
                                static_cast<float>(c[2]));
    if (has_uv) {
      // Texture coordinates come last on the line (after optional colours of varying count).
      const std::size_t n = line.tokens.size();
      const auto u = parse_double(line.tokens[n - 2]);
      const auto v = parse_double(line.tokens[n - 1]);
      if (!u || !v)
        throw InputError(file,
                         fmt::format("vertex {} (line {}): texture coordinates are not numbers", i,
                                     line.number));
      if (const std::string problem = non_finite_problem({*u, *v}, "texture coordinate");
          !problem.empty())
        throw InputError(file, fmt::format("vertex {} (line {}) {}", i, line.number, problem));
      mesh.uvs.emplace_back(static_cast<float>(*u), static_cast<float>(*v));
    }
  }

  mesh.indices.reserve(3 * std::min(F, text.size() / 4 + 1));
  std::vector<std::uint32_t> face;
  for (std::size_t f = 0; f < F; ++f) {
    if (!reader.next(line))
      throw truncated(fmt::format("after all {} vertices and {} face{}", V, f, f == 1 ? "" : "s"));
    const auto n = parse_int(line.tokens[0]);
    if (!n || *n < 0)
      throw InputError(file, fmt::format("face {} (line {}): {} is not a vertex count", f,
                                         line.number, quote(line.tokens[0])));
    if (*n == 0)
      throw InputError(file, fmt::format("face {} (line {}) has no vertices", f, line.number));
    const auto count = static_cast<std::size_t>(*n);
    if (line.tokens.size() < count + 1) {
      if (reader.at_end()) throw truncated(fmt::format("inside face {} (line {})", f, line.number));
      throw InputError(file, fmt::format("face {} (line {}) declares {} vertices but lists {}", f,
                                         line.number, count, line.tokens.size() - 1));
    }
    face.clear();
    for (std::size_t k = 0; k < count; ++k) {
      const auto idx = parse_int(line.tokens[k + 1]);
      if (!idx)
        throw InputError(file, fmt::format("face {} (line {}): {} is not a vertex index", f,
                                           line.number, quote(line.tokens[k + 1])));
      if (*idx < 0 || *idx >= static_cast<std::int64_t>(V))
        throw InputError(file, fmt::format("face {} (line {}) references vertex {} but the header "
                                           "declares {} vertices",
                                           f, line.number, *idx, V));
      face.push_back(static_cast<std::uint32_t>(*idx));
    }
    // Faces of one or two vertices become degenerate triangles, so that validation drops and
    // counts them with the others; polygons are fanned (OFF polygons are convex in practice).
    if (count < 3) {
      mesh.indices.insert(mesh.indices.end(), {face[0], face[count - 1], face[count - 1]});
    } else {
      for (std::size_t k = 1; k + 1 < count; ++k)
        mesh.indices.insert(mesh.indices.end(), {face[0], face[k], face[k + 1]});
    }
  }
  return mesh;
}

// ---- OBJ pre-scan ---------------------------------------------------------------------------
// assimp parses OBJ, but it reads "nan" as some number and reports an out-of-range index
// without saying where. This scan names the element and line first.

void prescan_obj(const fs::path& file, std::string_view text) {
  std::size_t totals[3] = {0, 0, 0};  // v, vt, vn
  {
    LineReader reader(text, /*continuations=*/true);
    Line line;
    while (reader.next(line)) {
      const std::string_view k = line.tokens[0];
      if (k == "v")
        ++totals[0];
      else if (k == "vt")
        ++totals[1];
      else if (k == "vn")
        ++totals[2];
    }
  }
  static constexpr const char* kWhat[3] = {"vertex", "texture coordinate", "normal"};
  std::size_t seen[3] = {0, 0, 0};
  std::size_t faces = 0;
  LineReader reader(text, /*continuations=*/true);
  Line line;
  while (reader.next(line)) {
    const std::string_view k = line.tokens[0];
    if (k == "v") {
      const std::size_t i = seen[0]++;
      if (line.tokens.size() < 4)
        throw InputError(file, fmt::format("vertex {} (line {}) has {} coordinates, expected 3", i,
                                           line.number, line.tokens.size() - 1));
      double c[3];
      for (int a = 0; a < 3; ++a) {
        const auto value = parse_double(line.tokens[static_cast<std::size_t>(a) + 1]);
        if (!value)
          throw InputError(file,
                           fmt::format("vertex {} (line {}): {} is not a number", i, line.number,
                                       quote(line.tokens[static_cast<std::size_t>(a) + 1])));
        c[a] = *value;
      }
      if (const std::string problem = non_finite_problem({c[0], c[1], c[2]}, "coordinate");
          !problem.empty())
        throw InputError(file, fmt::format("vertex {} (line {}) {}", i, line.number, problem));
    } else if (k == "vt") {
      const std::size_t i = seen[1]++;
      for (std::size_t a = 1; a < std::min<std::size_t>(line.tokens.size(), 3); ++a) {
        const auto value = parse_double(line.tokens[a]);
        if (value && std::isnan(*value))
          throw InputError(file,
                           fmt::format("texture coordinate {} (line {}) is NaN", i, line.number));
      }
    } else if (k == "vn") {
      ++seen[2];
    } else if (k == "f" || k == "l" || k == "p") {
      const std::size_t f = faces++;
      for (std::size_t t = 1; t < line.tokens.size(); ++t) {
        std::string_view ref = line.tokens[t];
        for (int slot = 0; slot < 3 && !ref.empty(); ++slot) {
          const std::size_t slash = ref.find('/');
          const std::string_view part = ref.substr(0, slash);
          ref = slash == std::string_view::npos ? std::string_view{} : ref.substr(slash + 1);
          if (part.empty()) continue;
          const auto idx = parse_int(part);
          if (!idx)
            throw InputError(file, fmt::format("face {} (line {}): {} is not an index", f,
                                               line.number, quote(line.tokens[t])));
          // Negative indices count back from the last element defined so far.
          const std::int64_t resolved =
              *idx < 0 ? static_cast<std::int64_t>(seen[slot]) + *idx : *idx - 1;
          if (*idx == 0 || resolved < 0 || resolved >= static_cast<std::int64_t>(totals[slot]))
            throw InputError(file, fmt::format("face {} (line {}) references {} {} but the file "
                                               "defines {} (OBJ indices start at 1)",
                                               f, line.number, kWhat[slot], *idx, totals[slot]));
        }
      }
    }
  }
}

// ---- PLY pre-check ---------------------------------------------------------------------------
// assimp 5.2's PLY reader does not return on a header that lacks its 'end_header' line (a hang
// found by fuzzing, tests/fuzz/regressions/mesh/), so a file that starts as a PLY header must
// have that line. Anything else is left to assimp, which refuses it quickly.

void prescan_ply(const fs::path& file, std::string_view text) {
  std::size_t start = 0;
  while (start < text.size() && std::isspace(static_cast<unsigned char>(text[start]))) ++start;
  if (text.size() - start < 3) return;
  std::string magic(text.substr(start, 3));
  for (char& c : magic) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (magic != "ply") return;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
      line.remove_suffix(1);
    if (line == "end_header") return;
    pos = end + 1;
  }
  throw InputError(file, "the PLY header has no 'end_header' line (truncated, or not a PLY file)");
}

// ---- assimp ---------------------------------------------------------------------------------

/// Checks the raw import (before any post-processing reads the indices).
void check_raw_scene(const fs::path& file, const aiScene& scene) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      if (const std::string problem = non_finite_problem({p.x, p.y, p.z}, "coordinate");
          !problem.empty())
        throw InputError(file, fmt::format("mesh {}, vertex {} {}", m, v, problem));
      if (mesh.HasTextureCoords(0)) {
        const aiVector3D& uv = mesh.mTextureCoords[0][v];
        if (std::isnan(uv.x) || std::isnan(uv.y))
          throw InputError(file,
                           fmt::format("mesh {}, vertex {} has a NaN texture coordinate", m, v));
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices == 0 || face.mIndices == nullptr)
        throw InputError(file,
                         fmt::format("mesh {}, face {} has no vertices (a truncated file?)", m, f));
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= mesh.mNumVertices)
          throw InputError(file, fmt::format("mesh {}, face {} references vertex {} but the mesh "
                                             "has {} vertices",
                                             m, f, face.mIndices[k], mesh.mNumVertices));
    }
  }
}

struct Piece {
  const aiMesh* mesh;
  aiMatrix4x4 transform;
  const aiNode* node = nullptr;
};

void collect_pieces(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                    std::vector<Piece>& out, int depth) {
  if (depth > 256) return;  // malformed, cyclic node graphs
  const aiMatrix4x4 xf = parent * node.mTransformation;
  for (unsigned i = 0; i < node.mNumMeshes; ++i)
    if (node.mMeshes[i] < scene.mNumMeshes)
      out.push_back({scene.mMeshes[node.mMeshes[i]], xf, &node});
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    if (node.mChildren[c]) collect_pieces(scene, *node.mChildren[c], xf, out, depth + 1);
}

std::string piece_group_name(const aiScene& scene, const Piece& piece, MeshGroupKey key) {
  std::string name;
  if (key == MeshGroupKey::kMaterial) {
    if (piece.mesh->mMaterialIndex < scene.mNumMaterials)
      name = scene.mMaterials[piece.mesh->mMaterialIndex]->GetName().C_Str();
  } else {
    if (piece.node) name = piece.node->mName.C_Str();
    if (name.empty()) name = piece.mesh->mName.C_Str();
  }
  return name.empty() ? "(unnamed)" : name;
}

/// With `groups`, the triangles' part ids are their group indices and `groups` their names.
Mesh read_with_assimp(const fs::path& file, MeshGroupKey key = MeshGroupKey::kMaterial,
                      std::vector<std::string>* groups = nullptr) {
  Assimp::Importer importer;
  // Import without post-processing first: our checks must see the raw indices, since
  // post-processing steps index vertex arrays without bounds checks.
  const aiScene* scene = importer.ReadFile(file.string(), 0);
  if (!scene)
    throw InputError(file, fmt::format("assimp cannot import it: {}", importer.GetErrorString()));
  check_raw_scene(file, *scene);
  // JoinIdenticalVertices compares every attribute (UVs included), so UV seams stay split.
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (!scene)
    throw InputError(file, fmt::format("assimp cannot import it: {}", importer.GetErrorString()));

  std::vector<Piece> pieces;
  if (scene->mRootNode) {
    collect_pieces(*scene, *scene->mRootNode, aiMatrix4x4(), pieces, 0);
  } else {
    for (unsigned m = 0; m < scene->mNumMeshes; ++m)
      pieces.push_back({scene->mMeshes[m], aiMatrix4x4()});
  }
  bool any_uv = false;
  for (const Piece& piece : pieces) any_uv = any_uv || piece.mesh->HasTextureCoords(0);

  Mesh out;
  std::map<std::string, std::uint16_t> group_index;
  for (const Piece& piece : pieces) {
    const aiMesh& m = *piece.mesh;
    const std::size_t offset = out.positions.size();
    std::uint16_t group = 0;
    if (groups) {
      const std::string name = piece_group_name(*scene, piece, key);
      const auto it = group_index.find(name);
      if (it != group_index.end()) {
        group = it->second;
      } else {
        if (groups->size() > std::numeric_limits<std::uint16_t>::max())
          throw InputError(file, fmt::format("more than {} groups",
                                             std::numeric_limits<std::uint16_t>::max() + 1));
        group = static_cast<std::uint16_t>(groups->size());
        group_index.emplace(name, group);
        groups->push_back(name);
      }
    }
    if (offset + m.mNumVertices > std::numeric_limits<std::uint32_t>::max())
      throw InputError(file, "too many vertices for 32-bit indices");
    const bool identity = piece.transform.IsIdentity();
    for (unsigned v = 0; v < m.mNumVertices; ++v) {
      const aiVector3D p = identity ? m.mVertices[v] : piece.transform * m.mVertices[v];
      out.positions.emplace_back(p.x, p.y, p.z);
      if (any_uv) {
        out.uvs.push_back(m.HasTextureCoords(0)
                              ? Vec2(m.mTextureCoords[0][v].x, m.mTextureCoords[0][v].y)
                              : Vec2(0.f));
      }
    }
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
      const aiFace& face = m.mFaces[f];
      const auto at = [&](unsigned k) {
        return static_cast<std::uint32_t>(offset +
                                          face.mIndices[std::min(k, face.mNumIndices - 1)]);
      };
      // Points and lines become degenerate triangles so that validation counts them.
      if (face.mNumIndices <= 3) {
        out.indices.insert(out.indices.end(), {at(0), at(1), at(2)});
      } else {
        for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
          out.indices.insert(out.indices.end(), {at(0), at(k), at(k + 1)});
      }
    }
    if (groups) out.triangle_part.resize(out.triangle_count(), group);
  }
  return out;
}

template <typename T>
void compact(std::vector<T>& values, const std::vector<std::uint32_t>& remap, std::size_t kept) {
  if (values.empty()) return;
  std::vector<T> out(kept);
  for (std::size_t v = 0; v < remap.size(); ++v)
    if (remap[v] != UINT32_MAX) out[remap[v]] = values[v];
  values = std::move(out);
}

template <typename T>
std::string finite_problem_vec(const T& value, const char* what) {
  for (int k = 0; k < T::length(); ++k)
    if (std::isnan(value[k])) return fmt::format("has a NaN {}", what);
  for (int k = 0; k < T::length(); ++k)
    if (!std::isfinite(value[k])) return fmt::format("has an infinite {}", what);
  return {};
}

}  // namespace

void validate_mesh(Mesh& mesh, const fs::path& source, MeshLoadReport* report) {
  const std::size_t V = mesh.vertex_count();
  if (V == 0) throw InputError(source, "empty mesh: no vertices");
  if (mesh.indices.empty()) throw InputError(source, "empty mesh: no triangles");
  if (mesh.indices.size() % 3 != 0)
    throw InputError(source,
                     fmt::format("index count {} is not a multiple of 3", mesh.indices.size()));
  const auto check_size = [&](std::size_t n, std::size_t expected, const char* what) {
    if (n != 0 && n != expected)
      throw InputError(source, fmt::format("has {} {} for {} elements", n, what, expected));
  };
  check_size(mesh.normals.size(), V, "normals");
  check_size(mesh.uvs.size(), V, "UVs");
  check_size(mesh.tangents.size(), V, "tangents");
  check_size(mesh.triangle_part.size(), mesh.triangle_count(), "part ids");

  const auto check_finite = [&](const auto& values, const char* what) {
    for (std::size_t v = 0; v < values.size(); ++v)
      if (const std::string problem = finite_problem_vec(values[v], what); !problem.empty())
        throw InputError(source, fmt::format("vertex {} {}", v, problem));
  };
  check_finite(mesh.positions, "coordinate");
  check_finite(mesh.uvs, "texture coordinate");
  check_finite(mesh.normals, "normal");
  check_finite(mesh.tangents, "tangent");

  const std::size_t T = mesh.triangle_count();
  for (std::size_t t = 0; t < T; ++t)
    for (int c = 0; c < 3; ++c)
      if (mesh.indices[3 * t + static_cast<std::size_t>(c)] >= V)
        throw InputError(
            source, fmt::format("triangle {} references vertex {} but the mesh has {} vertices", t,
                                mesh.indices[3 * t + static_cast<std::size_t>(c)], V));

  // Degenerate triangles: a repeated index, or exactly zero area. The cross product of float
  // positions is exact in double up to the last subtraction, so "zero" means collinear.
  std::size_t dropped = 0, first = 0, kept = 0;
  for (std::size_t t = 0; t < T; ++t) {
    const std::uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1],
                        c = mesh.indices[3 * t + 2];
    bool degenerate = a == b || b == c || a == c;
    if (!degenerate) {
      const Vec3d pa(mesh.positions[a]);
      const Vec3d cross = glm::cross(Vec3d(mesh.positions[b]) - pa, Vec3d(mesh.positions[c]) - pa);
      degenerate = cross == Vec3d(0.0);
    }
    if (degenerate) {
      if (dropped++ == 0) first = t;
      continue;
    }
    mesh.indices[3 * kept] = a;
    mesh.indices[3 * kept + 1] = b;
    mesh.indices[3 * kept + 2] = c;
    if (!mesh.triangle_part.empty()) mesh.triangle_part[kept] = mesh.triangle_part[t];
    ++kept;
  }
  if (dropped > 0) {
    mesh.indices.resize(3 * kept);
    if (!mesh.triangle_part.empty()) mesh.triangle_part.resize(kept);
    log_warn_named(
        "degenerate-triangles",
        "{}: dropped {} degenerate triangle{} (repeated vertex or zero area); the first is "
        "triangle {}",
        source.string(), dropped, dropped == 1 ? "" : "s", first);
    if (kept == 0)
      throw InputError(source, fmt::format("empty mesh: all {} triangles are degenerate", T));
  }

  // Remove unused vertices, keeping the order of the rest.
  std::vector<std::uint32_t> remap(V, UINT32_MAX);
  for (std::uint32_t i : mesh.indices) remap[i] = 0;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < V; ++v)
    if (remap[v] == 0) remap[v] = next++;
  const std::size_t unused = V - next;
  if (unused > 0) {
    for (std::uint32_t& i : mesh.indices) i = remap[i];
    compact(mesh.positions, remap, next);
    compact(mesh.normals, remap, next);
    compact(mesh.uvs, remap, next);
    compact(mesh.tangents, remap, next);
    log_info("{}: removed {} unused vertices", source.string(), unused);
  }
  if (report) {
    report->degenerate_dropped = dropped;
    report->first_degenerate = first;
    report->unused_vertices_removed = unused;
  }
}

GroupedMesh load_mesh_groups(const fs::path& file, MeshGroupKey key, MeshLoadReport* report) {
  const std::string ext = lower_extension(file);
  if (ext == ".off")
    throw InputError(file, "an OFF file has no material or object groups to select from");
  if (ext == ".obj") {
    prescan_obj(file, read_whole_file(file));
  } else if (ext == ".ply") {
    prescan_ply(file, read_whole_file(file));
  } else {
    std::error_code ec;
    if (!fs::exists(file, ec)) throw InputError(file, "file not found");
  }
  GroupedMesh out;
  out.mesh = read_with_assimp(file, key, &out.groups);
  MeshLoadReport local;
  validate_mesh(out.mesh, file, &local);
  if (report) *report = local;
  compute_smooth_normals(out.mesh);
  compute_tangents(out.mesh);
  return out;
}

Mesh load_mesh(const fs::path& file, MeshLoadReport* report) {
  const std::string ext = lower_extension(file);
  Mesh mesh;
  if (ext == ".off") {
    mesh = read_off(file, read_whole_file(file));
  } else {
    if (ext == ".obj") {
      prescan_obj(file, read_whole_file(file));
    } else if (ext == ".ply") {
      prescan_ply(file, read_whole_file(file));
    } else {
      std::error_code ec;
      if (!fs::exists(file, ec)) throw InputError(file, "file not found");
    }
    mesh = read_with_assimp(file);
  }
  MeshLoadReport local;
  validate_mesh(mesh, file, &local);
  if (report) *report = local;
  compute_smooth_normals(mesh);
  compute_tangents(mesh);
  return mesh;
}

void save_mesh_obj(const Mesh& mesh, const fs::path& file) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "# prtlab mesh: {} vertices, {} triangles\n",
                 mesh.vertex_count(), mesh.triangle_count());
  // fmt's default float format is the shortest string that reads back to the same float.
  for (const Vec3& p : mesh.positions)
    fmt::format_to(std::back_inserter(out), "v {} {} {}\n", p.x, p.y, p.z);
  for (const Vec2& uv : mesh.uvs) fmt::format_to(std::back_inserter(out), "vt {} {}\n", uv.x, uv.y);
  for (const Vec3& n : mesh.normals)
    fmt::format_to(std::back_inserter(out), "vn {} {} {}\n", n.x, n.y, n.z);
  const bool uv = mesh.has_uvs(), nrm = !mesh.normals.empty();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    out.push_back('f');
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t i = mesh.indices[3 * t + static_cast<std::size_t>(c)] + 1;
      if (uv && nrm)
        fmt::format_to(std::back_inserter(out), " {}/{}/{}", i, i, i);
      else if (uv)
        fmt::format_to(std::back_inserter(out), " {}/{}", i, i);
      else if (nrm)
        fmt::format_to(std::back_inserter(out), " {}//{}", i, i);
      else
        fmt::format_to(std::back_inserter(out), " {}", i);
    }
    out.push_back('\n');
  }
  write_text_atomically(file, std::string_view(out.data(), out.size()));
}

}  // namespace prt
