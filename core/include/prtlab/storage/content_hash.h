#pragma once
// Content hashes: XXH3-128 (xxHash 0.8) for stage-cache keys and archive checksums.
//
// A cache key is the digest of everything a stage's output depends on: the stage's own format
// version, its parameters and the content (not the name) of its inputs. Hasher makes that
// easy to get right:
//   - add(bytes) feeds raw bytes with no framing (use it for one blob of known meaning);
//   - every typed add is self-delimiting, so ("ab","c") and ("a","bc") hash differently:
//     strings and arrays carry a length prefix, scalars have a fixed width;
//   - the order of the adds matters (a digest of a sequence, not of a set).
// Numbers are hashed as their little-endian byte pattern (floating-point values by their bit
// pattern: -0.0 and 0.0 give different keys, which only costs a recompute). The digest of a
// given sequence is the same on every (little-endian) machine and in every build.
#include <array>
#include <bit>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <glm/fwd.hpp>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace prt {

static_assert(std::endian::native == std::endian::little,
              "prtlab hashes and archives assume a little-endian machine");

/// A 128-bit XXH3 digest. hex() is the canonical form printed by `xxhsum -H2` / `xxh128sum`
/// (high 64 bits first, big-endian, 32 lowercase hex digits).
struct Hash128 {
  std::uint64_t high = 0;
  std::uint64_t low = 0;

  std::string hex() const;
  /// Parses 32 hex digits (either case); throws ParameterError otherwise.
  static Hash128 from_hex(std::string_view hex);
  /// The 16 bytes of hex(), in the same order (how archives store a checksum).
  std::array<std::byte, 16> canonical_bytes() const;
  static Hash128 from_canonical_bytes(std::span<const std::byte, 16> bytes);

  friend auto operator<=>(const Hash128&, const Hash128&) = default;
};

/// Types whose arrays are hashed by their object bytes: arithmetic types, types without
/// padding (std::has_unique_object_representations) and glm vectors of arithmetic types
/// (no padding either). Specialise for your own padding-free aggregates if needed.
template <typename T>
inline constexpr bool kHashableAsBytes = (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) ||
                                         std::has_unique_object_representations_v<T>;
template <glm::length_t L, typename T, glm::qualifier Q>
inline constexpr bool kHashableAsBytes<glm::vec<L, T, Q>> =
    std::is_arithmetic_v<T> && sizeof(glm::vec<L, T, Q>) == L * sizeof(T);

/// Incremental XXH3-128 (seed 0). Cheap to create; copyable (a copy continues independently,
/// handy for a common prefix). digest() does not reset: more data may be added afterwards.
class Hasher {
 public:
  Hasher();
  ~Hasher();
  Hasher(const Hasher& other);
  Hasher& operator=(const Hasher& other);
  Hasher(Hasher&&) noexcept;
  Hasher& operator=(Hasher&&) noexcept;

  /// Raw bytes, no length prefix: add(a) then add(b) equals add(a ++ b).
  Hasher& add(std::span<const std::byte> bytes);

  /// A scalar by its fixed-width little-endian bytes. bool is hashed as one byte 0/1.
  template <typename T>
  requires std::is_arithmetic_v<T> Hasher& add(T value) {
    if constexpr (std::is_same_v<T, bool>) {
      const std::uint8_t b = value ? 1 : 0;
      return add(std::as_bytes(std::span(&b, 1)));
    } else {
      return add(std::as_bytes(std::span(&value, 1)));
    }
  }

  /// A string: u64 byte length, then the bytes.
  Hasher& add(std::string_view text);
  Hasher& add(const char* text) { return add(std::string_view(text)); }
  Hasher& add(const std::string& text) { return add(std::string_view(text)); }

  /// Another digest (its 16 canonical bytes), to chain keys of earlier stages.
  Hasher& add(const Hash128& hash);

  /// An array: u64 element count, u64 element size, then the element bytes.
  template <typename T>
  requires kHashableAsBytes<T> Hasher& add_array(std::span<const T> values) {
    add(static_cast<std::uint64_t>(values.size()));
    add(static_cast<std::uint64_t>(sizeof(T)));
    return add(std::as_bytes(values));
  }
  template <typename T>
  requires kHashableAsBytes<T> Hasher& add_array(const std::vector<T>& values) {
    return add_array(std::span<const T>(values));
  }

  /// A file's content (u64 length, then its bytes), streamed. Throws InputError if unreadable.
  Hasher& add_file(const std::filesystem::path& file);

  Hash128 digest() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// One-shot XXH3-128 of a byte range (identical to Hasher().add(bytes).digest()).
Hash128 hash_bytes(std::span<const std::byte> bytes);

}  // namespace prt
