#pragma once
// Archive sections of small indices (cluster ids, ...) stored in the narrowest unsigned type that
// holds every value below a known count: u8 up to 256 values, u16 up to 65,536, else u32. The
// reader checks every id against the count, because kernels index with them unchecked and a
// consistent checksum does not make a value in range.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace prt {

class ArchiveWriter;
class ArchiveReader;

/// Bytes an id below `count` takes in a section: 1, 2 or 4.
std::size_t index_bytes(std::uint64_t count);

/// Writes `ids`, each below `count`, as one section of index_bytes(count)-byte values.
void add_index_section(ArchiveWriter& archive, std::string name, std::span<const std::uint32_t> ids,
                       std::uint64_t count);

/// Reads the `n` ids add_index_section wrote with the same `count`. InputError naming the file
/// and the section when the section is missing or of another size, or an id is >= count.
std::vector<std::uint32_t> read_index_section(const ArchiveReader& archive, const std::string& name,
                                              std::uint64_t n, std::uint64_t count);

}  // namespace prt
