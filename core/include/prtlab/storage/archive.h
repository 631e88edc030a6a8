#pragma once
// The prtlab archive: one binary container for every artifact prtlab stores on disk (transfer
// matrices, compressed transfers, stage-cache entries). docs/file-format.md gives the exact
// byte layout; in short:
//
//   header   magic "PRTLAB\0\1", format version, file length, artifact kind + kind version,
//            metadata (a JSON object)
//   sections named typed arrays (name, element type, count, byte length), each payload
//            aligned to 16 bytes
//   trailer  "PRTLEND\0", file length again, XXH3-128 of every byte before the checksum
//
// Reading verifies the magic, the length and the checksum over the whole file BEFORE it parses
// anything, so a corrupt or truncated file is never half-read. Every problem is an InputError
// naming the file and the problem ("truncated: expected N bytes, file has M", "checksum
// mismatch (file corrupt)", "section 'cols' holds uint32 but uint16 was requested", ...).
//
// Versions: the archive format version (kArchiveFormatVersion) covers the container; each
// artifact kind carries its own kind version, bumped by its owner whenever the meaning or the
// set of its sections changes. Readers refuse newer versions than they know.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/storage/content_hash.h"

namespace prt {

/// Version of the container layout written by this build (readers accept 1..this).
inline constexpr std::uint32_t kArchiveFormatVersion = 1;
/// Pass as max_kind_version to accept any version of the expected kind.
inline constexpr std::uint32_t kAnyKindVersion = std::numeric_limits<std::uint32_t>::max();
/// Pass as expected_count to section() to accept any element count.
inline constexpr std::uint64_t kAnyCount = std::numeric_limits<std::uint64_t>::max();

/// Element type of a section, stored as one byte. Values are part of the file format.
enum class ElementType : std::uint8_t {
  kUInt8 = 1,
  kInt8 = 2,
  kUInt16 = 3,
  kInt16 = 4,
  kUInt32 = 5,
  kInt32 = 6,
  kUInt64 = 7,
  kInt64 = 8,
  kFloat32 = 9,
  kFloat64 = 10,
};

/// "uint8", "int8", ..., "float32", "float64"; "unknown(N)" for a value outside the enum.
std::string element_type_name(ElementType type);
/// Bytes per element (0 for a value outside the enum).
std::size_t element_size(ElementType type);

/// Types a section can hold: fixed-size integers and IEEE floats, unqualified (bool and long
/// double are excluded; std::byte is stored as uint8).
template <typename T>
concept ArchiveElement = std::is_same_v<T, std::remove_cv_t<T>> &&
    (std::is_same_v<T, std::byte> ||
     (std::is_integral_v<T> && !std::is_same_v<T, bool> &&
      (sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8)) ||
     (std::is_floating_point_v<T> && std::numeric_limits<T>::is_iec559 &&
      (sizeof(T) == 4 || sizeof(T) == 8)));

template <ArchiveElement T>
constexpr ElementType element_type_of() {
  if constexpr (std::is_same_v<T, std::byte>) {
    return ElementType::kUInt8;
  } else if constexpr (std::is_floating_point_v<T>) {
    return sizeof(T) == 4 ? ElementType::kFloat32 : ElementType::kFloat64;
  } else {
    constexpr bool s = std::is_signed_v<T>;
    switch (sizeof(T)) {
      case 1:
        return s ? ElementType::kInt8 : ElementType::kUInt8;
      case 2:
        return s ? ElementType::kInt16 : ElementType::kUInt16;
      case 4:
        return s ? ElementType::kInt32 : ElementType::kUInt32;
      default:
        return s ? ElementType::kInt64 : ElementType::kUInt64;
    }
  }
}

/// What the reader knows about one section.
struct SectionInfo {
  std::string name;
  ElementType type;
  std::uint64_t count;   ///< elements
  std::uint64_t offset;  ///< byte offset of the payload in the file (a multiple of 16)
  std::uint64_t bytes;   ///< payload bytes = count * element_size(type)
};

/// Builds an archive in memory (section data is copied, or moved in from an rvalue vector) and
/// writes it in one streaming pass. Section order is the order of add_section calls.
class ArchiveWriter {
 public:
  /// kind: 1..255 bytes, e.g. "transfer-matrix". The metadata starts with "written_by"
  /// (prtlab version and git hash); it holds no time stamp, so equal inputs give equal files.
  ArchiveWriter(std::string kind, std::uint32_t kind_version);

  /// Sets one metadata entry (replaces an existing key).
  ArchiveWriter& add_meta(const std::string& key, nlohmann::json value);
  /// The whole metadata object, for nested edits.
  nlohmann::json& meta() { return meta_; }
  const nlohmann::json& meta() const { return meta_; }

  /// Adds a section. name: 1..255 bytes, unique in the archive (ParameterError otherwise).
  template <ArchiveElement T, std::size_t E>
  ArchiveWriter& add_section(std::string name, std::span<const T, E> values) {
    return add_vector<T>(std::move(name),
                         std::make_shared<std::vector<T>>(values.begin(), values.end()));
  }
  template <ArchiveElement T, std::size_t E>
  ArchiveWriter& add_section(std::string name, std::span<T, E> values) {
    return add_section(std::move(name), std::span<const T, E>(values));
  }
  template <ArchiveElement T>
  ArchiveWriter& add_section(std::string name, const std::vector<T>& values) {
    return add_section(std::move(name), std::span<const T>(values));
  }
  /// Takes the vector over: no copy.
  template <ArchiveElement T>
  ArchiveWriter& add_section(std::string name, std::vector<T>&& values) {
    return add_vector<T>(std::move(name), std::make_shared<std::vector<T>>(std::move(values)));
  }

  /// Indices stored as u16 when `narrow` (every value must fit: ParameterError otherwise), else
  /// as u32; read back with ArchiveReader::indices().
  ArchiveWriter& add_indices(std::string name, std::span<const std::uint32_t> values, bool narrow);

  const std::string& kind() const { return kind_; }
  std::uint32_t kind_version() const { return kind_version_; }
  bool has_section(std::string_view name) const;
  /// Exact size of the file write() produces.
  std::uint64_t size_bytes() const;

  /// Writes atomically (temporary file + rename, see atomic_file.h): on any failure the
  /// destination is left as it was. Throws InputError naming the file.
  void write(const std::filesystem::path& file) const;
  /// The bytes write() would produce.
  std::vector<std::byte> to_bytes() const;
  /// Streams the archive; `name` is used in error messages.
  void write_to(std::ostream& out, const std::filesystem::path& name) const;

  /// Receives the archive bytes in order (internal; public so the implementation can name it).
  using Sink = std::function<void(std::span<const std::byte>)>;

 private:
  void emit(const Sink& sink) const;
  struct Section {
    std::string name;
    ElementType type;
    std::uint64_t count;
    std::span<const std::byte> bytes;
    std::shared_ptr<const void> owner;  // keeps `bytes` alive
  };
  template <ArchiveElement T>
  ArchiveWriter& add_vector(std::string name, std::shared_ptr<const std::vector<T>> owned) {
    // Both are taken before `owned` is moved into the call (argument order is unspecified).
    const auto bytes = std::as_bytes(std::span<const T>(*owned));
    const std::uint64_t count = owned->size();
    return add_owned(std::move(name), element_type_of<T>(), count, bytes, std::move(owned));
  }
  ArchiveWriter& add_owned(std::string name, ElementType type, std::uint64_t count,
                           std::span<const std::byte> bytes, std::shared_ptr<const void> owner);
  std::string meta_text() const;

  std::string kind_;
  std::uint32_t kind_version_;
  nlohmann::json meta_;
  std::vector<Section> sections_;
};

/// A verified archive held in memory. Cheap to move and copy; views stay valid while it (or a
/// copy) lives. open() maps the file: the cache and the writer only ever replace files by
/// rename, so a mapped archive never changes under the reader; truncating a file in place
/// while it is being read (outside prtlab) would end the process with SIGBUS.
class ArchiveReader {
 public:
  /// Reads and verifies `file`. expected_kind empty: any kind (check later with expect_kind).
  static ArchiveReader open(const std::filesystem::path& file, std::string_view expected_kind = {},
                            std::uint32_t max_kind_version = kAnyKindVersion);
  /// Verifies and parses archive bytes that are already in memory; `name` is used in messages.
  static ArchiveReader from_bytes(std::span<const std::byte> bytes,
                                  const std::filesystem::path& name,
                                  std::string_view expected_kind = {},
                                  std::uint32_t max_kind_version = kAnyKindVersion);

  /// Throws InputError "artifact kind is 'x', expected 'y'" or "'y' version 3 is newer than
  /// this build supports (2)".
  void expect_kind(std::string_view kind, std::uint32_t max_kind_version = kAnyKindVersion) const;

  const std::filesystem::path& path() const { return path_; }
  std::uint32_t format_version() const { return format_version_; }
  /// Indices stored as u16 when `narrow` (every value must fit: ParameterError otherwise), else
  /// as u32; read back with ArchiveReader::indices().
  ArchiveWriter& add_indices(std::string name, std::span<const std::uint32_t> values, bool narrow);

  const std::string& kind() const { return kind_; }
  std::uint32_t kind_version() const { return kind_version_; }
  std::uint64_t size_bytes() const { return size_; }
  /// The checksum stored in (and verified against) the trailer: a content id of the file.
  const Hash128& checksum() const { return checksum_; }

  const nlohmann::json& meta() const { return meta_; }
  /// meta()[key] converted to T; InputError when the key is missing or of another type.
  template <typename T>
  T meta_value(const std::string& key) const {
    const auto it = meta_.find(key);
    if (it == meta_.end()) throw InputError(path_, "metadata key '" + key + "' missing");
    try {
      return it->template get<T>();
    } catch (const nlohmann::json::exception& e) {
      throw InputError(path_, "metadata key '" + key + "' has the wrong type (" + e.what() + ")");
    }
  }

  const std::vector<SectionInfo>& sections() const { return sections_; }
  bool has_section(std::string_view name) const;
  /// InputError "section 'x' missing (present: a, b)" when absent.
  const SectionInfo& section_info(std::string_view name) const;

  /// Zero-copy view of a section's payload, valid while this reader lives. Checks the element
  /// type (and the count unless kAnyCount) and throws InputError naming both on a mismatch.
  template <ArchiveElement T>
  std::span<const T> view(std::string_view name, std::uint64_t expected_count = kAnyCount) const {
    const SectionInfo& info = checked(name, element_type_of<T>(), expected_count);
    return {reinterpret_cast<const T*>(data_.get() + info.offset),
            static_cast<std::size_t>(info.count)};
  }
  /// A copy of a section's payload, with the same checks as view().
  template <ArchiveElement T>
  std::vector<T> section(std::string_view name, std::uint64_t expected_count = kAnyCount) const {
    const auto v = view<T>(name, expected_count);
    return std::vector<T>(v.begin(), v.end());
  }

  /// An index section written by add_indices (u16 or u32), widened to u32, with the count
  /// checked as view() does.
  std::vector<std::uint32_t> indices(std::string_view name,
                                     std::uint64_t expected_count = kAnyCount) const;

  // Copies share the (immutable) file contents.
  ArchiveReader(const ArchiveReader&);
  ArchiveReader& operator=(const ArchiveReader&);
  ArchiveReader(ArchiveReader&&) noexcept;
  ArchiveReader& operator=(ArchiveReader&&) noexcept;
  ~ArchiveReader();

 private:
  ArchiveReader() = default;
  void parse(std::string_view expected_kind, std::uint32_t max_kind_version);
  const SectionInfo& checked(std::string_view name, ElementType type,
                             std::uint64_t expected_count) const;

  std::filesystem::path path_;
  // The whole file: a read-only private mapping for open() (no copy: on this kind of machine
  // mapping + hashing runs several times faster than read() into fresh memory), a heap copy for
  // from_bytes(). Either way 16-byte aligned, so payloads can be viewed in place.
  std::shared_ptr<const std::byte> data_;
  std::uint64_t size_ = 0;
  std::uint32_t format_version_ = 0;
  std::string kind_;
  std::uint32_t kind_version_ = 0;
  nlohmann::json meta_;
  std::vector<SectionInfo> sections_;
  Hash128 checksum_;
};

}  // namespace prt
