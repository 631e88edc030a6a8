#include "prtlab/storage/archive.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <functional>
#include <set>

#include "prtlab/base/build_info.h"
#include "prtlab/storage/atomic_file.h"

namespace prt {
namespace {

// The envelope: these offsets and the trailer never change between format versions, so any
// build can tell "newer version" from "corrupt" (see docs/file-format.md).
constexpr std::array<unsigned char, 8> kMagic = {'P', 'R', 'T', 'L', 'A', 'B', 0, 1};
constexpr std::array<unsigned char, 8> kEndMagic = {'P', 'R', 'T', 'L', 'E', 'N', 'D', 0};
constexpr std::uint64_t kVersionOffset = 8;
constexpr std::uint64_t kHeaderLengthOffset = 12;
constexpr std::uint64_t kFileLengthOffset = 16;
constexpr std::uint64_t kKindVersionOffset = 24;
constexpr std::uint64_t kSectionCountOffset = 28;
constexpr std::uint64_t kKindLengthOffset = 32;
constexpr std::uint64_t kMetaLengthOffset = 36;
constexpr std::uint64_t kFixedHeaderBytes = 40;
constexpr std::uint64_t kSectionRecordBytes = 24;
constexpr std::uint64_t kTrailerBytes = 32;
constexpr std::uint64_t kChecksumBytes = 16;
constexpr std::uint64_t kAlign = 16;
constexpr std::size_t kMaxNameBytes = 255;
// Smallest possible archive: fixed header + 1-byte kind + "{}" padded, and the trailer.
constexpr std::uint64_t kMinArchiveBytes = 48 + kTrailerBytes;

constexpr std::uint64_t align_up(std::uint64_t x) {
  return (x + kAlign - 1) & ~(kAlign - 1);
}

template <typename T>
T load_le(const std::byte* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

template <typename T>
std::array<std::byte, sizeof(T)> le_bytes(T v) {
  std::array<std::byte, sizeof(T)> out;
  std::memcpy(out.data(), &v, sizeof(T));
  return out;
}

bool matches(const std::byte* p, const std::array<unsigned char, 8>& magic, std::size_t n = 8) {
  return std::memcmp(p, magic.data(), n) == 0;
}

// Feeds the archive bytes to a sink while hashing them, and tracks the offset for padding.
using Sink = ArchiveWriter::Sink;

class Emitter {
 public:
  explicit Emitter(const Sink& sink) : sink_(sink) {}
  void put(std::span<const std::byte> bytes) {
    hasher_.add(bytes);
    sink_(bytes);
    offset_ += bytes.size();
  }
  template <typename T>
  void put_le(T v) {
    const auto b = le_bytes(v);
    put(b);
  }
  void put_text(std::string_view s) { put(std::as_bytes(std::span(s.data(), s.size()))); }
  void pad() {
    static constexpr std::array<std::byte, kAlign> kZeros{};
    put(std::span(kZeros.data(), align_up(offset_) - offset_));
  }
  // The checksum is not part of what it covers.
  void put_checksum() {
    const auto c = hasher_.digest().canonical_bytes();
    sink_(c);
    offset_ += c.size();
  }
  std::uint64_t offset() const { return offset_; }

 private:
  const Sink& sink_;
  Hasher hasher_;
  std::uint64_t offset_ = 0;
};

}  // namespace

std::string element_type_name(ElementType type) {
  switch (type) {
    case ElementType::kUInt8:
      return "uint8";
    case ElementType::kInt8:
      return "int8";
    case ElementType::kUInt16:
      return "uint16";
    case ElementType::kInt16:
      return "int16";
    case ElementType::kUInt32:
      return "uint32";
    case ElementType::kInt32:
      return "int32";
    case ElementType::kUInt64:
      return "uint64";
    case ElementType::kInt64:
      return "int64";
    case ElementType::kFloat32:
      return "float32";
    case ElementType::kFloat64:
      return "float64";
  }
  return fmt::format("unknown({})", static_cast<int>(type));
}

std::size_t element_size(ElementType type) {
  switch (type) {
    case ElementType::kUInt8:
    case ElementType::kInt8:
      return 1;
    case ElementType::kUInt16:
    case ElementType::kInt16:
      return 2;
    case ElementType::kUInt32:
    case ElementType::kInt32:
    case ElementType::kFloat32:
      return 4;
    case ElementType::kUInt64:
    case ElementType::kInt64:
    case ElementType::kFloat64:
      return 8;
  }
  return 0;
}

// ---------------------------------------------------------------------------------- writer

ArchiveWriter::ArchiveWriter(std::string kind, std::uint32_t kind_version)
    : kind_(std::move(kind)), kind_version_(kind_version), meta_(nlohmann::json::object()) {
  if (kind_.empty() || kind_.size() > kMaxNameBytes)
    throw ParameterError(
        fmt::format("archive kind '{}' must be 1 to {} bytes long", kind_, kMaxNameBytes));
  const BuildInfo& b = build_info();
  meta_["written_by"] = {{"prtlab", b.version}, {"git", b.git_hash}};
}

ArchiveWriter& ArchiveWriter::add_meta(const std::string& key, nlohmann::json value) {
  if (key.empty()) throw ParameterError("archive metadata keys must not be empty");
  meta_[key] = std::move(value);
  return *this;
}

bool ArchiveWriter::has_section(std::string_view name) const {
  return std::any_of(sections_.begin(), sections_.end(),
                     [&](const Section& s) { return s.name == name; });
}

ArchiveWriter& ArchiveWriter::add_owned(std::string name, ElementType type, std::uint64_t count,
                                        std::span<const std::byte> bytes,
                                        std::shared_ptr<const void> owner) {
  if (name.empty() || name.size() > kMaxNameBytes)
    throw ParameterError(
        fmt::format("archive section name '{}' must be 1 to {} bytes long", name, kMaxNameBytes));
  if (has_section(name))
    throw ParameterError(fmt::format("archive section '{}' added twice (kind '{}')", name, kind_));
  PRT_CHECK(bytes.size() == count * element_size(type), "section '{}' byte size mismatch", name);
  sections_.push_back({std::move(name), type, count, bytes, std::move(owner)});
  return *this;
}

std::string ArchiveWriter::meta_text() const {
  if (!meta_.is_object()) throw ParameterError("archive metadata must be a JSON object");
  try {
    return meta_.dump();
  } catch (const nlohmann::json::exception& e) {
    throw ParameterError(fmt::format("archive metadata cannot be written: {}", e.what()));
  }
}

std::uint64_t ArchiveWriter::size_bytes() const {
  std::uint64_t off = align_up(kFixedHeaderBytes + kind_.size() + meta_text().size());
  for (const Section& s : sections_)
    off = align_up(align_up(off + kSectionRecordBytes + s.name.size()) + s.bytes.size());
  return off + kTrailerBytes;
}

void ArchiveWriter::write_to(std::ostream& out, const std::filesystem::path& name) const {
  emit([&](std::span<const std::byte> bytes) {
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    if (!out) throw InputError(name, "write failed (disk full?)");
  });
}

void ArchiveWriter::emit(const Sink& sink) const {
  const std::string meta = meta_text();
  const std::uint64_t total = size_bytes();
  const std::uint64_t header_bytes = align_up(kFixedHeaderBytes + kind_.size() + meta.size());
  PRT_CHECK(header_bytes <= std::numeric_limits<std::uint32_t>::max(), "metadata too large");
  Emitter e(sink);
  e.put(std::as_bytes(std::span(kMagic)));
  e.put_le<std::uint32_t>(kArchiveFormatVersion);
  e.put_le<std::uint32_t>(static_cast<std::uint32_t>(header_bytes));
  e.put_le<std::uint64_t>(total);
  e.put_le<std::uint32_t>(kind_version_);
  e.put_le<std::uint32_t>(static_cast<std::uint32_t>(sections_.size()));
  e.put_le<std::uint32_t>(static_cast<std::uint32_t>(kind_.size()));
  e.put_le<std::uint32_t>(static_cast<std::uint32_t>(meta.size()));
  e.put_text(kind_);
  e.put_text(meta);
  e.pad();
  for (const Section& s : sections_) {
    e.put_le<std::uint32_t>(static_cast<std::uint32_t>(s.name.size()));
    e.put_le<std::uint8_t>(static_cast<std::uint8_t>(s.type));
    e.put(std::array<std::byte, 3>{});
    e.put_le<std::uint64_t>(s.count);
    e.put_le<std::uint64_t>(s.bytes.size());
    e.put_text(s.name);
    e.pad();
    e.put(s.bytes);
    e.pad();
  }
  e.put(std::as_bytes(std::span(kEndMagic)));
  e.put_le<std::uint64_t>(total);
  e.put_checksum();
  PRT_CHECK(e.offset() == total, "archive size {} differs from the computed {}", e.offset(), total);
}

void ArchiveWriter::write(const std::filesystem::path& file) const {
  write_file_atomically(file, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(tmp, "cannot open for writing");
    write_to(out, file);
    out.close();
    if (!out) throw InputError(file, "write failed (disk full?)");
  });
}

std::vector<std::byte> ArchiveWriter::to_bytes() const {
  std::vector<std::byte> out;
  out.reserve(size_bytes());
  emit([&](std::span<const std::byte> b) { out.insert(out.end(), b.begin(), b.end()); });
  return out;
}

// ---------------------------------------------------------------------------------- reader

ArchiveReader::ArchiveReader(const ArchiveReader&) = default;
ArchiveReader& ArchiveReader::operator=(const ArchiveReader&) = default;
ArchiveReader::ArchiveReader(ArchiveReader&&) noexcept = default;
ArchiveReader& ArchiveReader::operator=(ArchiveReader&&) noexcept = default;
ArchiveReader::~ArchiveReader() = default;

namespace {

std::shared_ptr<const std::byte> heap_copy(std::span<const std::byte> bytes) {
  std::shared_ptr<std::byte[]> buffer =
      std::make_shared_for_overwrite<std::byte[]>(std::max<std::size_t>(bytes.size(), 1));
  std::copy(bytes.begin(), bytes.end(), buffer.get());
  return std::shared_ptr<const std::byte>(buffer, buffer.get());
}

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// Maps the whole file (MAP_POPULATE: it is about to be hashed end to end); falls back to
// read() for files that cannot be mapped.
std::shared_ptr<const std::byte> load_file(const std::filesystem::path& file, std::uint64_t& size) {
  const FileDescriptor fd(::open(file.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) throw InputError(file, fmt::format("cannot open: {}", std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0)
    throw InputError(file, fmt::format("cannot read: {}", std::strerror(errno)));
  if (S_ISDIR(st.st_mode)) throw InputError(file, "is a directory, not an archive");
  size = static_cast<std::uint64_t>(st.st_size);
  if (S_ISREG(st.st_mode) && size > 0) {
    void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd.get(), 0);
    if (p != MAP_FAILED) {
      return std::shared_ptr<const std::byte>(
          static_cast<const std::byte*>(p),
          [size](const std::byte* q) { ::munmap(const_cast<std::byte*>(q), size); });
    }
  }
  std::shared_ptr<std::byte[]> buffer =
      std::make_shared_for_overwrite<std::byte[]>(std::max<std::uint64_t>(size, 1));
  std::uint64_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(fd.get(), buffer.get() + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(file, fmt::format("read error: {}", std::strerror(errno)));
    if (n == 0) break;
    got += static_cast<std::uint64_t>(n);
  }
  if (got != size)
    throw InputError(
        file, fmt::format("read {} of {} bytes (the file changed while being read)", got, size));
  return std::shared_ptr<const std::byte>(buffer, buffer.get());
}

}  // namespace

ArchiveReader ArchiveReader::open(const std::filesystem::path& file, std::string_view expected_kind,
                                  std::uint32_t max_kind_version) {
  ArchiveReader r;
  r.path_ = file;
  r.data_ = load_file(file, r.size_);
  r.parse(expected_kind, max_kind_version);
  return r;
}

ArchiveReader ArchiveReader::from_bytes(std::span<const std::byte> bytes,
                                        const std::filesystem::path& name,
                                        std::string_view expected_kind,
                                        std::uint32_t max_kind_version) {
  ArchiveReader r;
  r.path_ = name;
  r.data_ = heap_copy(bytes);
  r.size_ = bytes.size();
  r.parse(expected_kind, max_kind_version);
  return r;
}

void ArchiveReader::parse(std::string_view expected_kind, std::uint32_t max_kind_version) {
  const std::byte* d = data_.get();
  const std::uint64_t m = size_;
  PRT_CHECK(reinterpret_cast<std::uintptr_t>(d) % kAlign == 0, "archive buffer is not aligned");
  const auto malformed = [&](const std::string& what) {
    return InputError(path_, fmt::format("malformed archive (file corrupt): {}", what));
  };

  // 1. Envelope: magic, then length, then checksum; nothing else is trusted before that.
  if (m == 0) throw InputError(path_, "empty file (not a prtlab archive)");
  if (!matches(d, kMagic, std::min<std::uint64_t>(m, kMagic.size())))
    throw InputError(path_, "not a prtlab archive (it does not start with the PRTLAB magic)");
  if (m < kFileLengthOffset + 8)
    throw InputError(path_, fmt::format("truncated: file has {} bytes, the smallest archive has {}",
                                        m, kMinArchiveBytes));
  const std::uint64_t length = load_le<std::uint64_t>(d + kFileLengthOffset);
  const auto trailer_fits = [&](std::uint64_t end) {
    return end >= kMinArchiveBytes && end <= m && matches(d + end - kTrailerBytes, kEndMagic) &&
           load_le<std::uint64_t>(d + end - kTrailerBytes + 8) == end;
  };
  if (length != m) {
    // A complete trailer at the end of the file means the length in the header was damaged.
    if (trailer_fits(m)) throw InputError(path_, "checksum mismatch (file corrupt)");
    if (length > m)
      throw InputError(path_, fmt::format("truncated: expected {} bytes, file has {}", length, m));
    if (trailer_fits(length))
      throw InputError(path_,
                       fmt::format("{} bytes of unexpected data after the end of the archive "
                                   "(expected {} bytes, file has {})",
                                   m - length, length, m));
    throw InputError(path_, "checksum mismatch (file corrupt)");
  }
  if (m < kMinArchiveBytes)
    throw InputError(path_, fmt::format("truncated: file has {} bytes, the smallest archive has {}",
                                        m, kMinArchiveBytes));
  const std::uint64_t checked_bytes = m - kChecksumBytes;
  checksum_ = Hash128::from_canonical_bytes(std::span<const std::byte, 16>(d + checked_bytes, 16));
  if (hash_bytes(std::span(d, checked_bytes)) != checksum_)
    throw InputError(path_, "checksum mismatch (file corrupt)");
  if (!trailer_fits(m)) throw malformed("bad trailer");

  // 2. Versions.
  format_version_ = load_le<std::uint32_t>(d + kVersionOffset);
  if (format_version_ > kArchiveFormatVersion)
    throw InputError(path_, fmt::format("format version {} is newer than this build supports ({}); "
                                        "update prtlab or delete the file",
                                        format_version_, kArchiveFormatVersion));
  if (format_version_ == 0) throw malformed("format version 0");

  // 3. Header.
  const std::uint64_t end = m - kTrailerBytes;
  const std::uint64_t header_bytes = load_le<std::uint32_t>(d + kHeaderLengthOffset);
  kind_version_ = load_le<std::uint32_t>(d + kKindVersionOffset);
  const std::uint32_t section_count = load_le<std::uint32_t>(d + kSectionCountOffset);
  const std::uint64_t kind_bytes = load_le<std::uint32_t>(d + kKindLengthOffset);
  const std::uint64_t meta_bytes = load_le<std::uint32_t>(d + kMetaLengthOffset);
  if (header_bytes % kAlign != 0 || header_bytes > end ||
      kFixedHeaderBytes + kind_bytes + meta_bytes > header_bytes)
    throw malformed(fmt::format("header length {} does not fit", header_bytes));
  if (kind_bytes == 0 || kind_bytes > kMaxNameBytes) throw malformed("bad artifact kind length");
  kind_.assign(reinterpret_cast<const char*>(d + kFixedHeaderBytes), kind_bytes);
  const auto* meta_begin = reinterpret_cast<const char*>(d + kFixedHeaderBytes + kind_bytes);
  try {
    meta_ = nlohmann::json::parse(meta_begin, meta_begin + meta_bytes);
  } catch (const nlohmann::json::exception& e) {
    throw malformed(fmt::format("metadata is not valid JSON ({})", e.what()));
  }
  if (!meta_.is_object()) throw malformed("metadata is not a JSON object");

  // 4. Sections.
  std::set<std::string, std::less<>> names;
  std::uint64_t off = header_bytes;
  if (section_count > (end - header_bytes) / kSectionRecordBytes)
    throw malformed(fmt::format("{} sections cannot fit in the file", section_count));
  sections_.reserve(section_count);
  for (std::uint32_t i = 0; i < section_count; ++i) {
    if (end - off < kSectionRecordBytes)
      throw malformed(fmt::format("section {} runs past the end", i));
    const std::uint64_t name_bytes = load_le<std::uint32_t>(d + off);
    const auto type = static_cast<ElementType>(load_le<std::uint8_t>(d + off + 4));
    const std::uint64_t count = load_le<std::uint64_t>(d + off + 8);
    const std::uint64_t bytes = load_le<std::uint64_t>(d + off + 16);
    if (name_bytes == 0 || name_bytes > kMaxNameBytes ||
        end - off - kSectionRecordBytes < name_bytes)
      throw malformed(fmt::format("section {} has a bad name length {}", i, name_bytes));
    std::string name(reinterpret_cast<const char*>(d + off + kSectionRecordBytes), name_bytes);
    const std::size_t esize = element_size(type);
    if (esize == 0)
      throw malformed(
          fmt::format("section '{}' has unknown element type {}", name, static_cast<int>(type)));
    if (bytes % esize != 0 || bytes / esize != count)
      throw malformed(fmt::format("section '{}' holds {} bytes, not {} {} elements", name, bytes,
                                  count, element_type_name(type)));
    const std::uint64_t payload = align_up(off + kSectionRecordBytes + name_bytes);
    if (payload > end || end - payload < bytes)
      throw malformed(fmt::format("section '{}' runs past the end", name));
    if (!names.insert(name).second)
      throw malformed(fmt::format("section '{}' appears twice", name));
    sections_.push_back({std::move(name), type, count, payload, bytes});
    off = align_up(payload + bytes);
  }
  if (off != end)
    throw malformed(fmt::format("{} unexpected bytes after the last section", end - off));

  expect_kind(expected_kind, max_kind_version);
}

void ArchiveReader::expect_kind(std::string_view kind, std::uint32_t max_kind_version) const {
  if (!kind.empty() && kind != kind_)
    throw InputError(path_, fmt::format("artifact kind is '{}', expected '{}'", kind_, kind));
  if (kind_version_ > max_kind_version)
    throw InputError(path_, fmt::format("'{}' version {} is newer than this build supports ({}); "
                                        "update prtlab or delete the file",
                                        kind_, kind_version_, max_kind_version));
}

bool ArchiveReader::has_section(std::string_view name) const {
  return std::any_of(sections_.begin(), sections_.end(),
                     [&](const SectionInfo& s) { return s.name == name; });
}

const SectionInfo& ArchiveReader::section_info(std::string_view name) const {
  for (const SectionInfo& s : sections_)
    if (s.name == name) return s;
  std::string present;
  for (const SectionInfo& s : sections_) present += (present.empty() ? "" : ", ") + s.name;
  throw InputError(path_, fmt::format("section '{}' missing (sections present: {})", name,
                                      present.empty() ? "none" : present));
}

const SectionInfo& ArchiveReader::checked(std::string_view name, ElementType type,
                                          std::uint64_t expected_count) const {
  const SectionInfo& info = section_info(name);
  if (info.type != type)
    throw InputError(path_, fmt::format("section '{}' holds {} but {} was requested", name,
                                        element_type_name(info.type), element_type_name(type)));
  if (expected_count != kAnyCount && info.count != expected_count)
    throw InputError(path_, fmt::format("section '{}' has {} elements, expected {}", name,
                                        info.count, expected_count));
  return info;
}

ArchiveWriter& ArchiveWriter::add_indices(std::string name, std::span<const std::uint32_t> values,
                                          bool narrow) {
  if (!narrow) return add_section(std::move(name), values);
  std::vector<std::uint16_t> v16(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (values[i] > 0xffffu)
      throw ParameterError(
          fmt::format("archive section '{}': index {} does not fit u16", name, values[i]));
    v16[i] = static_cast<std::uint16_t>(values[i]);
  }
  return add_section(std::move(name), std::move(v16));
}

std::vector<std::uint32_t> ArchiveReader::indices(std::string_view name,
                                                  std::uint64_t expected_count) const {
  if (section_info(name).type == ElementType::kUInt16) {
    const auto v = view<std::uint16_t>(name, expected_count);
    return {v.begin(), v.end()};
  }
  return section<std::uint32_t>(name, expected_count);
}

}  // namespace prt
