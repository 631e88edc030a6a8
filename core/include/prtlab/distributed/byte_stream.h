#pragma once
// The messages ranks exchange: plain values and arrays appended to a byte buffer, and read back
// in the same order (same machine kind on every rank: no byte-order conversion). A read past the
// end throws with the message's name.
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "prtlab/base/error.h"

namespace prt {

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(&out) {}
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void put(const T& x) {
    const auto* b = reinterpret_cast<const std::uint8_t*>(&x);
    out_->insert(out_->end(), b, b + sizeof x);
  }
  /// u64 count, then the elements.
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void put_array(std::span<const T> xs) {
    put<std::uint64_t>(xs.size());
    const auto* b = reinterpret_cast<const std::uint8_t*>(xs.data());
    out_->insert(out_->end(), b, b + xs.size_bytes());
  }
  template <class T>
  void put_array(const std::vector<T>& xs) {
    put_array(std::span<const T>(xs));
  }

 private:
  std::vector<std::uint8_t>* out_;
};

class ByteReader {
 public:
  ByteReader(std::span<const std::uint8_t> in, std::string what)
      : in_(in), what_(std::move(what)) {}
  template <class T>
  requires std::is_trivially_copyable_v<T> T get() {
    T x;
    take(&x, sizeof x);
    return x;
  }
  template <class T>
  requires std::is_trivially_copyable_v<T> std::vector<T> get_array() {
    const auto n = get<std::uint64_t>();
    PRT_CHECK(n <= (in_.size() - at_) / sizeof(T), "{}: a truncated message", what_);
    std::vector<T> xs(static_cast<std::size_t>(n));
    take(xs.data(), xs.size() * sizeof(T));
    return xs;
  }
  bool done() const { return at_ == in_.size(); }

 private:
  void take(void* dst, std::size_t n) {
    PRT_CHECK(at_ + n <= in_.size(), "{}: a truncated message", what_);
    if (n) std::memcpy(dst, in_.data() + at_, n);
    at_ += n;
  }
  std::span<const std::uint8_t> in_;
  std::string what_;
  std::size_t at_ = 0;
};

}  // namespace prt
