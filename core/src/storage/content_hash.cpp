#include "prtlab/storage/content_hash.h"

#include <xxhash.h>

#include <cstdio>
#include <new>

#include "prtlab/base/error.h"

namespace prt {

// The state lives behind the library's own allocator (it wants 64-byte alignment and its
// layout is only public under XXH_STATIC_LINKING_ONLY).
struct Hasher::State {
  State() : xxh(XXH3_createState()) {
    if (!xxh) throw std::bad_alloc();
  }
  ~State() { XXH3_freeState(xxh); }
  State(const State&) = delete;
  State& operator=(const State&) = delete;
  XXH3_state_t* xxh;
};

namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::string Hash128::hex() const {
  return fmt::format("{:016x}{:016x}", high, low);
}

Hash128 Hash128::from_hex(std::string_view hex) {
  if (hex.size() != 32)
    throw ParameterError(fmt::format("'{}' is not a 128-bit hash (expected 32 hex digits, got {})",
                                     hex, hex.size()));
  Hash128 h;
  for (std::size_t i = 0; i < 32; ++i) {
    const int v = hex_value(hex[i]);
    if (v < 0)
      throw ParameterError(fmt::format("'{}' is not a 128-bit hash (bad digit '{}')", hex, hex[i]));
    std::uint64_t& word = i < 16 ? h.high : h.low;
    word = (word << 4) | static_cast<std::uint64_t>(v);
  }
  return h;
}

std::array<std::byte, 16> Hash128::canonical_bytes() const {
  std::array<std::byte, 16> out;
  for (int i = 0; i < 8; ++i) {
    out[i] = static_cast<std::byte>(high >> (56 - 8 * i));
    out[8 + i] = static_cast<std::byte>(low >> (56 - 8 * i));
  }
  return out;
}

Hash128 Hash128::from_canonical_bytes(std::span<const std::byte, 16> bytes) {
  Hash128 h;
  for (int i = 0; i < 8; ++i) {
    h.high = (h.high << 8) | std::to_integer<std::uint64_t>(bytes[i]);
    h.low = (h.low << 8) | std::to_integer<std::uint64_t>(bytes[8 + i]);
  }
  return h;
}

Hasher::Hasher() : state_(std::make_unique<State>()) {
  XXH3_128bits_reset(state_->xxh);
}
Hasher::~Hasher() = default;
Hasher::Hasher(const Hasher& other) : state_(std::make_unique<State>()) {
  PRT_CHECK(other.state_, "copy of a moved-from Hasher");
  XXH3_copyState(state_->xxh, other.state_->xxh);
}
Hasher& Hasher::operator=(const Hasher& other) {
  PRT_CHECK(other.state_, "copy of a moved-from Hasher");
  if (this == &other) return *this;
  if (!state_) state_ = std::make_unique<State>();
  XXH3_copyState(state_->xxh, other.state_->xxh);
  return *this;
}
Hasher::Hasher(Hasher&&) noexcept = default;
Hasher& Hasher::operator=(Hasher&&) noexcept = default;

Hasher& Hasher::add(std::span<const std::byte> bytes) {
  PRT_CHECK(state_, "use of a moved-from Hasher");
  XXH3_128bits_update(state_->xxh, bytes.data(), bytes.size());
  return *this;
}

Hasher& Hasher::add(std::string_view text) {
  add(static_cast<std::uint64_t>(text.size()));
  return add(std::as_bytes(std::span(text.data(), text.size())));
}

Hasher& Hasher::add(const Hash128& hash) {
  const auto bytes = hash.canonical_bytes();
  return add(std::span<const std::byte>(bytes));
}

Hasher& Hasher::add_file(const std::filesystem::path& file) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) throw InputError(file, fmt::format("cannot hash: {}", ec.message()));
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(file, "cannot open for reading");
  add(static_cast<std::uint64_t>(size));
  std::vector<std::byte> buffer(1 << 20);
  std::uint64_t total = 0;
  for (;;) {
    const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), f.get());
    total += n;
    add(std::span<const std::byte>(buffer.data(), n));
    if (n < buffer.size()) break;
  }
  if (std::ferror(f.get())) throw InputError(file, "read error while hashing");
  if (total != size)
    throw InputError(file,
                     fmt::format("changed while being hashed ({} bytes, then {})", size, total));
  return *this;
}

Hash128 Hasher::digest() const {
  PRT_CHECK(state_, "use of a moved-from Hasher");
  const XXH128_hash_t h = XXH3_128bits_digest(state_->xxh);
  return Hash128{h.high64, h.low64};
}

Hash128 hash_bytes(std::span<const std::byte> bytes) {
  const XXH128_hash_t h = XXH3_128bits(bytes.data(), bytes.size());
  return Hash128{h.high64, h.low64};
}

}  // namespace prt
