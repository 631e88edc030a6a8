// Content hashes (XXH3-128 against vectors from the xxhsum tool) and the prtlab archive: bit-exact
// round trips, the documented byte layout, and a precise, file-naming refusal of every kind of
// damaged or foreign file.
#include "prtlab/storage/archive.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/storage/content_hash.h"
#include "prtlab/storage/index_section.h"
#include "support/temp_dir.h"

namespace prt {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr std::uint64_t kSeed = 20240601;

std::span<const std::byte> bytes_of(std::string_view s) {
  return std::as_bytes(std::span(s.data(), s.size()));
}

// Constants from `xxhsum -H2` (xxHash 0.8.1), an implementation independent of this code.
constexpr const char* kXxh128Empty = "99aa06d3014798d86001c324468d497f";
constexpr const char* kXxh128Abc = "06b05ab6733a618578af5f94892f3950";
constexpr const char* kXxh128Fox = "ddd650205ca3e7fa24a1cc2e3a8a7651";  // "The quick brown fox..."
constexpr const char* kXxh128Pattern100 = "7f5a1f03462e52b4d61d8dbff22d515f";
constexpr const char* kXxh128Pattern10000 = "d53e809be21e616d441f01d9711bebed";

std::vector<std::byte> pattern(std::size_t n) {
  std::vector<std::byte> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::byte>((i * 31 + 7) % 256);
  return v;
}

// ------------------------------------------------------------------------------------ Hasher

TEST(Hasher, MatchesXxhsumVectors) {
  EXPECT_EQ(Hasher().digest().hex(), kXxh128Empty);
  EXPECT_EQ(hash_bytes({}).hex(), kXxh128Empty);
  EXPECT_EQ(Hasher().add(bytes_of("abc")).digest().hex(), kXxh128Abc);
  EXPECT_EQ(hash_bytes(bytes_of("The quick brown fox jumps over the lazy dog")).hex(), kXxh128Fox);
  EXPECT_EQ(hash_bytes(pattern(100)).hex(), kXxh128Pattern100);
  EXPECT_EQ(hash_bytes(pattern(10000)).hex(), kXxh128Pattern10000);
}

TEST(Hasher, StreamingEqualsOneShotForAnySplit) {
  const auto data = pattern(10000);
  for (std::size_t split : {0u, 1u, 15u, 16u, 17u, 239u, 240u, 241u, 5000u, 9999u, 10000u}) {
    Hasher h;
    h.add(std::span(data).first(split)).add(std::span(data).subspan(split));
    EXPECT_EQ(h.digest().hex(), kXxh128Pattern10000) << "split at " << split;
  }
}

TEST(Hasher, TypedAddsUseTheDocumentedEncoding) {
  // Scalars: fixed-width little-endian bytes.
  const std::array<std::byte, 4> one_u32{std::byte{1}, std::byte{0}, std::byte{0}, std::byte{0}};
  EXPECT_EQ(Hasher().add(std::uint32_t{1}).digest(), hash_bytes(one_u32));
  const double x = 1.5;
  EXPECT_EQ(Hasher().add(x).digest(), hash_bytes(std::as_bytes(std::span(&x, 1))));
  EXPECT_EQ(Hasher().add(true).digest(), hash_bytes(std::array{std::byte{1}}));
  // Strings: u64 length, then the bytes.
  Hasher raw;
  raw.add(std::uint64_t{3}).add(bytes_of("abc"));
  EXPECT_EQ(Hasher().add("abc").digest(), raw.digest());
  EXPECT_EQ(Hasher().add(std::string("abc")).digest(), raw.digest());
  // Arrays: u64 count, u64 element size, then the bytes.
  const std::vector<float> v{1.0f, -2.0f, 3.5f};
  Hasher raw_array;
  raw_array.add(std::uint64_t{3}).add(std::uint64_t{4}).add(std::as_bytes(std::span(v)));
  EXPECT_EQ(Hasher().add_array(v).digest(), raw_array.digest());
  // Digests: their canonical bytes.
  const Hash128 abc = hash_bytes(bytes_of("abc"));
  const auto canon = abc.canonical_bytes();
  EXPECT_EQ(Hasher().add(abc).digest(), hash_bytes(canon));
}

TEST(Hasher, EveryFieldAndTheOrderMatter) {
  const auto key = [](std::string_view scene, std::uint32_t res, double eps, std::uint32_t ver) {
    return Hasher().add(scene).add(res).add(eps).add(ver).digest();
  };
  const Hash128 base = key("bunny", 32, 1e-3, 2);
  EXPECT_EQ(key("bunny", 32, 1e-3, 2), base);
  EXPECT_NE(key("bunnz", 32, 1e-3, 2), base);
  EXPECT_NE(key("bunny", 33, 1e-3, 2), base);
  EXPECT_NE(key("bunny", 32, std::nextafter(1e-3, 1.0), 2), base);  // one ulp
  EXPECT_NE(key("bunny", 32, 1e-3, 3), base);
  EXPECT_NE(Hasher().add(1).add(2).digest(), Hasher().add(2).add(1).digest());
  // Framing: the boundary between two strings is part of the content.
  EXPECT_NE(Hasher().add("ab").add("c").digest(), Hasher().add("a").add("bc").digest());
  // Width is part of a scalar: 1 as u32 is not 1 as u64.
  EXPECT_NE(Hasher().add(std::uint32_t{1}).digest(), Hasher().add(std::uint64_t{1}).digest());
  // Flipping any single bit of a buffer changes the digest.
  auto data = pattern(300);
  const Hash128 h0 = hash_bytes(data);
  for (std::size_t i = 0; i < data.size(); i += 7) {
    data[i] ^= std::byte{0x10};
    EXPECT_NE(hash_bytes(data), h0) << "byte " << i;
    data[i] ^= std::byte{0x10};
  }
  EXPECT_EQ(hash_bytes(data), h0);
}

TEST(Hasher, CopiesContinueIndependentlyAndDigestDoesNotReset) {
  Hasher prefix;
  prefix.add("scene").add(42);
  Hasher a = prefix, b = prefix;
  a.add("visibility");
  b.add("transfer");
  EXPECT_NE(a.digest(), b.digest());
  EXPECT_EQ(a.digest(), Hasher().add("scene").add(42).add("visibility").digest());
  Hasher c;
  c.add(bytes_of("ab"));
  (void)c.digest();
  c.add(bytes_of("c"));
  EXPECT_EQ(c.digest().hex(), kXxh128Abc);
  Hasher d;
  d = a;
  EXPECT_EQ(d.digest(), a.digest());
}

TEST(Hash128, HexRoundTripAndCanonicalBytes) {
  const Hash128 h = hash_bytes(bytes_of("abc"));
  EXPECT_EQ(Hash128::from_hex(h.hex()), h);
  EXPECT_EQ(Hash128::from_hex("06B05AB6733A618578AF5F94892F3950"), h);
  EXPECT_EQ(h.high, 0x06b05ab6733a6185ull);
  EXPECT_EQ(h.low, 0x78af5f94892f3950ull);
  const auto c = h.canonical_bytes();
  EXPECT_EQ(c[0], std::byte{0x06});
  EXPECT_EQ(c[15], std::byte{0x50});
  EXPECT_EQ(Hash128::from_canonical_bytes(c), h);
  EXPECT_THROW(Hash128::from_hex("abc"), ParameterError);
  EXPECT_THROW(Hash128::from_hex("06b05ab6733a618578af5f94892f395g"), ParameterError);
}

// ------------------------------------------------------------------------------------ files

using testing::TempDir;

std::vector<std::byte> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<char> c((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(c.size());
  std::memcpy(out.data(), c.data(), c.size());
  return out;
}

void write_raw(const fs::path& p, std::span<const std::byte> bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

template <typename T>
T load(const std::vector<std::byte>& b, std::size_t off) {
  T v;
  std::memcpy(&v, b.data() + off, sizeof(T));
  return v;
}

// Recomputes the trailer checksum after a deliberate edit, as a valid writer would have.
void reseal(std::vector<std::byte>& b) {
  const Hash128 h = hash_bytes(std::span(b).first(b.size() - 16));
  const auto c = h.canonical_bytes();
  std::copy(c.begin(), c.end(), b.end() - 16);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("unexpected exception type: ") + e.what();
  }
  return "no exception";
}

std::string open_error(const fs::path& p, std::string_view kind = {},
                       std::uint32_t max_version = kAnyKindVersion) {
  return error_of([&] { (void)ArchiveReader::open(p, kind, max_version); });
}

TEST(Hasher, AddFileHashesLengthThenContent) {
  TempDir dir;
  const auto data = pattern(3 << 20);  // spans several read chunks
  write_raw(dir / "blob", data);
  Hasher expected;
  expected.add(static_cast<std::uint64_t>(data.size())).add(data);
  EXPECT_EQ(Hasher().add_file(dir / "blob").digest(), expected.digest());
  write_raw(dir / "empty", {});
  EXPECT_EQ(Hasher().add_file(dir / "empty").digest(), Hasher().add(std::uint64_t{0}).digest());
  EXPECT_THAT(error_of([&] { Hasher().add_file(dir / "missing"); }),
              HasSubstr((dir / "missing").string()));
}

// A sample covering every element type, awkward float values and an empty section.
struct Sample {
  std::vector<std::uint8_t> u8{0, 1, 255, 128};
  std::vector<std::int8_t> i8{-128, 127, 0, -1, 5};
  std::vector<std::uint16_t> u16{0, 65535, 12345};
  std::vector<std::int16_t> i16{-32768, 32767};
  std::vector<std::uint32_t> u32;
  std::vector<std::int32_t> i32{std::numeric_limits<std::int32_t>::min(), 7};
  std::vector<std::uint64_t> u64{std::numeric_limits<std::uint64_t>::max(), 0, 1ull << 40};
  std::vector<std::int64_t> i64{std::numeric_limits<std::int64_t>::min(), -1};
  std::vector<float> f32{0.0f,
                         -0.0f,
                         1.5f,
                         std::numeric_limits<float>::denorm_min(),
                         std::numeric_limits<float>::infinity(),
                         std::bit_cast<float>(0x7fc12345u),  // NaN with a payload
                         std::numeric_limits<float>::max()};
  std::vector<double> f64;
  std::vector<std::byte> raw{std::byte{0xde}, std::byte{0xad}, std::byte{0xbe}, std::byte{0xef}};
  std::vector<float> empty;

  Sample() {
    std::mt19937_64 rng(kSeed);
    u32.resize(1000);
    for (auto& x : u32) x = static_cast<std::uint32_t>(rng());
    f64.resize(777);
    for (auto& x : f64) x = std::bit_cast<double>(rng());  // any bit pattern, NaNs included
  }

  ArchiveWriter writer() const {
    ArchiveWriter w("transfer-matrix", 2);
    w.add_meta("scene", "bunny");
    w.add_meta("parameters", {{"resolution", 32}, {"supersampling", 2}, {"eps", 1e-3}});
    w.add_section("u8", u8).add_section("i8", i8).add_section("u16", u16);
    w.add_section("i16", i16).add_section("u32", u32).add_section("i32", i32);
    w.add_section("u64", u64).add_section("i64", i64).add_section("f32", f32);
    w.add_section("f64", f64).add_section("raw", raw).add_section("empty", empty);
    return w;
  }
};

template <typename T>
void expect_bit_exact(const std::vector<T>& got, const std::vector<T>& want, const char* name) {
  ASSERT_EQ(got.size(), want.size()) << name;
  EXPECT_EQ(std::memcmp(got.data(), want.data(), want.size() * sizeof(T)), 0) << name;
}

TEST(Archive, RoundTripIsBitExact) {
  TempDir dir;
  const Sample s;
  const ArchiveWriter w = s.writer();
  const fs::path file = dir / "t.prt";
  w.write(file);
  const ArchiveReader r = ArchiveReader::open(file, "transfer-matrix", 2);
  EXPECT_EQ(r.kind(), "transfer-matrix");
  EXPECT_EQ(r.kind_version(), 2u);
  EXPECT_EQ(r.format_version(), kArchiveFormatVersion);
  EXPECT_EQ(r.path(), file);
  expect_bit_exact(r.section<std::uint8_t>("u8"), s.u8, "u8");
  expect_bit_exact(r.section<std::int8_t>("i8"), s.i8, "i8");
  expect_bit_exact(r.section<std::uint16_t>("u16"), s.u16, "u16");
  expect_bit_exact(r.section<std::int16_t>("i16"), s.i16, "i16");
  expect_bit_exact(r.section<std::uint32_t>("u32"), s.u32, "u32");
  expect_bit_exact(r.section<std::int32_t>("i32"), s.i32, "i32");
  expect_bit_exact(r.section<std::uint64_t>("u64"), s.u64, "u64");
  expect_bit_exact(r.section<std::int64_t>("i64"), s.i64, "i64");
  expect_bit_exact(r.section<float>("f32"), s.f32, "f32");
  expect_bit_exact(r.section<double>("f64"), s.f64, "f64");
  expect_bit_exact(r.section<std::byte>("raw"), s.raw, "raw");
  expect_bit_exact(r.section<std::uint8_t>("raw"),
                   std::vector<std::uint8_t>{0xde, 0xad, 0xbe, 0xef}, "raw as uint8");
  EXPECT_TRUE(r.section<float>("empty").empty());
  EXPECT_TRUE(r.has_section("f64"));
  EXPECT_FALSE(r.has_section("f65"));

  // Metadata comes back as written, plus the writer's provenance.
  EXPECT_EQ(r.meta().at("scene"), "bunny");
  EXPECT_EQ(r.meta().at("parameters"), w.meta().at("parameters"));
  EXPECT_EQ(r.meta(), w.meta());
  EXPECT_TRUE(r.meta().contains("written_by"));
  EXPECT_EQ(r.meta_value<std::string>("scene"), "bunny");
  EXPECT_EQ(r.meta_value<nlohmann::json>("parameters").at("resolution"), 32);
  EXPECT_THAT(error_of([&] { (void)r.meta_value<std::string>("sceen"); }),
              HasSubstr("metadata key 'sceen' missing"));
  EXPECT_THAT(error_of([&] { (void)r.meta_value<int>("scene"); }),
              HasSubstr("metadata key 'scene' has the wrong type"));

  // Sections in writing order, payloads 16-byte aligned, views zero-copy and aligned.
  ASSERT_EQ(r.sections().size(), 12u);
  EXPECT_EQ(r.sections().front().name, "u8");
  EXPECT_EQ(r.sections().back().name, "empty");
  for (const SectionInfo& info : r.sections()) {
    EXPECT_EQ(info.offset % 16, 0u) << info.name;
    EXPECT_EQ(info.bytes, info.count * element_size(info.type)) << info.name;
  }
  const auto view = r.view<double>("f64", s.f64.size());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(view.data()) % 16, 0u);
  EXPECT_EQ(std::memcmp(view.data(), s.f64.data(), s.f64.size() * sizeof(double)), 0);

  // The file is exactly what to_bytes() gives and size_bytes() predicts; reading the bytes
  // from memory gives the same archive.
  const auto bytes = read_file(file);
  EXPECT_EQ(bytes.size(), w.size_bytes());
  EXPECT_EQ(bytes, w.to_bytes());
  EXPECT_EQ(r.size_bytes(), bytes.size());
  const ArchiveReader m = ArchiveReader::from_bytes(bytes, "memory");
  EXPECT_EQ(m.checksum(), r.checksum());
  expect_bit_exact(m.section<double>("f64"), s.f64, "f64 from memory");
}

TEST(Archive, MovedInSectionsAreNotCopiedButStillRoundTrip) {
  std::vector<float> big(100000);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<float>(i) * 0.25f;
  const std::vector<float> expected = big;
  ArchiveWriter w("x", 1);
  w.add_section("values", std::move(big));
  std::array<std::int16_t, 3> mutable_data{-1, 0, 1};
  w.add_section("mutable_span", std::span(mutable_data));                    // span<T>
  w.add_section("const_span", std::span<const std::int16_t>(mutable_data));  // span<const T>
  const ArchiveReader r = ArchiveReader::from_bytes(w.to_bytes(), "mem");
  expect_bit_exact(r.section<float>("values"), expected, "values");
  EXPECT_EQ(r.section<std::int16_t>("mutable_span"), (std::vector<std::int16_t>{-1, 0, 1}));
  EXPECT_EQ(r.section<std::int16_t>("const_span"), (std::vector<std::int16_t>{-1, 0, 1}));
}

TEST(Archive, ByteLayoutIsTheDocumentedOne) {
  TempDir dir;
  ArchiveWriter w("transfer-matrix", 7);
  w.meta().erase("written_by");  // makes the bytes independent of the build
  w.add_meta("scene", "tiny");
  w.add_section("cols", std::vector<std::uint32_t>{1, 2, 3});
  w.add_section("values", std::vector<float>{0.25f, 0.5f});
  const fs::path file = dir / "layout.prt";
  w.write(file);
  const auto b = read_file(file);
  const std::string meta = R"({"scene":"tiny"})";
  // Header.
  ASSERT_GE(b.size(), 80u);
  EXPECT_EQ(std::memcmp(b.data(), "PRTLAB\0\1", 8), 0);
  EXPECT_EQ(load<std::uint32_t>(b, 8), 1u);  // format version
  const std::uint32_t header = load<std::uint32_t>(b, 12);
  EXPECT_EQ(header, 80u);  // 40 + 15 ("transfer-matrix") + 16 (metadata) = 71, padded to 16
  EXPECT_EQ(load<std::uint64_t>(b, 16), b.size());
  EXPECT_EQ(load<std::uint32_t>(b, 24), 7u);  // kind version
  EXPECT_EQ(load<std::uint32_t>(b, 28), 2u);  // sections
  EXPECT_EQ(load<std::uint32_t>(b, 32), 15u);
  EXPECT_EQ(load<std::uint32_t>(b, 36), meta.size());
  EXPECT_EQ(std::memcmp(b.data() + 40, "transfer-matrix", 15), 0);
  EXPECT_EQ(std::memcmp(b.data() + 55, meta.data(), meta.size()), 0);
  // First section record at the header length.
  std::size_t off = header;
  EXPECT_EQ(load<std::uint32_t>(b, off), 4u);     // name length
  EXPECT_EQ(load<std::uint8_t>(b, off + 4), 5u);  // uint32 tag
  EXPECT_EQ(load<std::uint64_t>(b, off + 8), 3u);
  EXPECT_EQ(load<std::uint64_t>(b, off + 16), 12u);
  EXPECT_EQ(std::memcmp(b.data() + off + 24, "cols", 4), 0);
  const std::size_t payload = off + 32;  // 24 + 4 rounded up to 16
  EXPECT_EQ(load<std::uint32_t>(b, payload + 8), 3u);
  off = payload + 16;  // 12 bytes of payload rounded up
  EXPECT_EQ(load<std::uint32_t>(b, off), 6u);
  EXPECT_EQ(load<std::uint8_t>(b, off + 4), 9u);  // float32 tag
  EXPECT_EQ(load<float>(b, off + 32 + 4), 0.5f);
  off = off + 32 + 16;
  // Trailer.
  EXPECT_EQ(off + 32, b.size());
  EXPECT_EQ(std::memcmp(b.data() + off, "PRTLEND\0", 8), 0);
  EXPECT_EQ(load<std::uint64_t>(b, off + 8), b.size());
  const auto c = hash_bytes(std::span(b).first(b.size() - 16)).canonical_bytes();
  EXPECT_EQ(std::memcmp(b.data() + off + 16, c.data(), 16), 0);
  // Golden: the file was rebuilt independently from docs/file-format.md (a Python struct.pack
  // script) and its first size-16 bytes hashed with `xxhsum -H2`; any change of the layout
  // must be a deliberate format version bump.
  EXPECT_EQ(b.size(), 208u);
  EXPECT_EQ(
      Hash128::from_canonical_bytes(std::span<const std::byte, 16>(b.data() + b.size() - 16, 16))
          .hex(),
      "226245c66bed3eaf41a647e6f8d9150a");
}

// ------------------------------------------------------------------------- damaged archives

class DamagedArchive : public ::testing::Test {
 protected:
  void SetUp() override {
    good_ = Sample().writer().to_bytes();
    file_ = dir_ / "damaged.prt";
  }
  std::string open_modified(const std::vector<std::byte>& bytes) {
    write_raw(file_, bytes);
    return open_error(file_);
  }
  TempDir dir_;
  std::vector<std::byte> good_;
  fs::path file_;
};

TEST_F(DamagedArchive, FlippedByteAnywhereIsACorruptFile) {
  const std::size_t n = good_.size();
  const ArchiveReader intact = ArchiveReader::from_bytes(good_, "intact");
  const SectionInfo& u32 = intact.section_info("u32");
  const std::vector<std::pair<std::size_t, const char*>> positions = {
      {8, "format version"},
      {12, "header length"},
      {16, "file length (low byte)"},
      {23, "file length (high byte)"},
      {24, "kind version"},
      {28, "section count"},
      {40, "kind string"},
      {60, "metadata"},
      {u32.offset - 10, "section record"},
      {u32.offset, "payload, first byte"},
      {u32.offset + u32.bytes / 2, "payload, middle"},
      {u32.offset + u32.bytes - 1, "payload, last byte"},
      {n - 33, "last padding byte"},
      {n - 32, "trailer end magic"},
      {n - 24, "trailer length"},
      {n - 16, "checksum, first byte"},
      {n - 1, "checksum, last byte"},
  };
  for (const auto& [pos, what] : positions) {
    for (const std::byte flip : {std::byte{0x01}, std::byte{0x80}}) {
      auto bad = good_;
      bad[pos] ^= flip;
      const std::string err = open_modified(bad);
      EXPECT_THAT(err, HasSubstr(file_.string())) << what;
      EXPECT_THAT(err, HasSubstr("checksum mismatch (file corrupt)")) << what << " at " << pos;
    }
  }
}

TEST_F(DamagedArchive, FlippedMagicIsNotAnArchive) {
  for (std::size_t pos = 0; pos < 8; ++pos) {
    auto bad = good_;
    bad[pos] ^= std::byte{0x20};
    EXPECT_THAT(open_modified(bad), HasSubstr("not a prtlab archive")) << pos;
  }
}

TEST_F(DamagedArchive, TruncationIsReportedWithBothLengths) {
  const std::size_t n = good_.size();
  for (std::size_t len :
       {std::size_t{24}, std::size_t{40}, std::size_t{100}, n / 2, n - 32, n - 17, n - 16, n - 1}) {
    const std::vector<std::byte> cut(good_.begin(),
                                     good_.begin() + static_cast<std::ptrdiff_t>(len));
    const std::string err = open_modified(cut);
    EXPECT_THAT(err, HasSubstr(file_.string()));
    EXPECT_THAT(err, HasSubstr(fmt::format("truncated: expected {} bytes, file has {}", n, len)))
        << "cut at " << len;
  }
  for (std::size_t len : {1, 5, 8, 23}) {
    const std::vector<std::byte> cut(good_.begin(),
                                     good_.begin() + static_cast<std::ptrdiff_t>(len));
    EXPECT_THAT(open_modified(cut), HasSubstr(fmt::format("truncated: file has {} bytes", len)));
  }
  EXPECT_THAT(open_modified({}), HasSubstr("empty file (not a prtlab archive)"));
}

TEST_F(DamagedArchive, AppendedBytesAreRefused) {
  auto longer = good_;
  longer.resize(good_.size() + 5, std::byte{0});
  EXPECT_THAT(open_modified(longer), HasSubstr("5 bytes of unexpected data after the end"));
}

TEST_F(DamagedArchive, ForeignFilesAreNotArchives) {
  std::mt19937_64 rng(kSeed);
  for (std::size_t n : {3, 100, 4096}) {
    std::vector<std::byte> noise(n);
    for (auto& b : noise) b = static_cast<std::byte>(rng());
    EXPECT_THAT(open_modified(noise), HasSubstr("not a prtlab archive")) << n << " random bytes";
  }
  const std::string text = "ply\nformat ascii 1.0\n";
  EXPECT_THAT(open_modified({reinterpret_cast<const std::byte*>(text.data()),
                             reinterpret_cast<const std::byte*>(text.data()) + text.size()}),
              HasSubstr("not a prtlab archive"));
  EXPECT_THAT(open_error(dir_ / "missing.prt"), HasSubstr((dir_ / "missing.prt").string()));
  EXPECT_THAT(open_error(dir_.path()), HasSubstr("is a directory"));
}

TEST_F(DamagedArchive, NewerFormatVersionIsRefusedNotCalledCorrupt) {
  auto newer = good_;
  const std::uint32_t v = kArchiveFormatVersion + 1;
  std::memcpy(newer.data() + 8, &v, 4);
  reseal(newer);
  EXPECT_THAT(open_modified(newer),
              HasSubstr(fmt::format("format version {} is newer than this build supports ({})", v,
                                    kArchiveFormatVersion)));
}

TEST_F(DamagedArchive, WrongKindAndNewerKindVersionAreRefused) {
  write_raw(file_, good_);
  EXPECT_THAT(open_error(file_, "compressed-transfer"),
              HasSubstr("artifact kind is 'transfer-matrix', expected 'compressed-transfer'"));
  EXPECT_THAT(open_error(file_, "transfer-matrix", 1),
              HasSubstr("'transfer-matrix' version 2 is newer than this build supports (1)"));
  EXPECT_EQ(open_error(file_, "transfer-matrix", 2), "no exception");
  const ArchiveReader r = ArchiveReader::open(file_);
  EXPECT_THAT(error_of([&] { r.expect_kind("x"); }),
              HasSubstr("artifact kind is 'transfer-matrix', expected 'x'"));
}

TEST_F(DamagedArchive, MissingSectionsAndWrongTypesAreNamed) {
  write_raw(file_, good_);
  const ArchiveReader r = ArchiveReader::open(file_, "transfer-matrix");
  const std::string missing = error_of([&] { (void)r.section<float>("values"); });
  EXPECT_THAT(missing, HasSubstr(file_.string()));
  EXPECT_THAT(missing, HasSubstr("section 'values' missing"));
  EXPECT_THAT(missing, HasSubstr("u8, i8"));
  EXPECT_THAT(error_of([&] { (void)r.section<std::uint16_t>("u32"); }),
              HasSubstr("section 'u32' holds uint32 but uint16 was requested"));
  EXPECT_THAT(error_of([&] { (void)r.view<float>("f64"); }),
              HasSubstr("section 'f64' holds float64 but float32 was requested"));
  EXPECT_THAT(error_of([&] { (void)r.section<std::int32_t>("u32"); }),
              HasSubstr("holds uint32 but int32 was requested"));
  EXPECT_THAT(error_of([&] { (void)r.section<std::uint32_t>("u32", 999); }),
              HasSubstr("section 'u32' has 1000 elements, expected 999"));
  EXPECT_EQ(r.section<std::uint32_t>("u32", 1000).size(), 1000u);
}

// A file with a valid checksum but inconsistent content (a buggy or hostile writer) is refused
// with an InputError, never read out of bounds (run under ASan to see the difference).
TEST_F(DamagedArchive, ResealedGarbageNeverCrashesTheParser) {
  std::mt19937_64 rng(kSeed);
  ArchiveWriter w("k", 1);
  w.add_section("a", std::vector<std::uint16_t>{1, 2, 3})
      .add_section("b", std::vector<double>{4.0});
  const auto base = w.to_bytes();
  int refused = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    auto bad = base;
    // Damage only the parsed region (not the envelope: magic, version, length, trailer).
    const std::size_t pos = 12 + rng() % (bad.size() - 32 - 12);
    if (pos >= 16 && pos < 24) continue;
    bad[pos] = static_cast<std::byte>(rng());
    if (bad == base) continue;
    reseal(bad);
    try {
      const ArchiveReader r = ArchiveReader::from_bytes(bad, "fuzz");
      for (const SectionInfo& s : r.sections()) EXPECT_LE(s.offset + s.bytes, bad.size() - 32);
    } catch (const InputError& e) {
      ++refused;
      EXPECT_THAT(e.what(), HasSubstr("fuzz"));
    }
  }
  EXPECT_GT(refused, 100);  // most single-byte edits of the structure are caught
}

TEST_F(DamagedArchive, SectionCountBeyondTheFileIsMalformed) {
  auto bad = good_;
  const std::uint32_t count = 13;
  std::memcpy(bad.data() + 28, &count, 4);
  reseal(bad);
  EXPECT_THAT(open_modified(bad), HasSubstr("malformed archive"));
}

// ------------------------------------------------------------------------------- the writer

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(ArchiveWriter, LeavesNoTemporaryFileAndNeverClobbersOnFailure) {
  TempDir dir;
  const fs::path file = dir / "good.prt";
  const Sample s;
  s.writer().write(file);
  EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"good.prt"});
  const auto good = read_file(file);

  // Failure inside the write (metadata that cannot be serialised: invalid UTF-8) after the
  // temporary file was opened.
  ArchiveWriter bad("transfer-matrix", 2);
  bad.add_section("values", std::vector<float>{1, 2, 3});
  bad.add_meta("scene", std::string("\xff\xfe bad utf-8"));
  EXPECT_THROW(bad.write(file), ParameterError);
  EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"good.prt"});
  EXPECT_EQ(read_file(file), good);
  EXPECT_EQ(ArchiveReader::open(file).section<std::uint32_t>("u32"), s.u32);

  // Destination in a directory that cannot exist (its parent is a regular file).
  const std::string err = error_of([&] { s.writer().write(file / "sub" / "x.prt"); });
  EXPECT_THAT(err, HasSubstr("good.prt"));
  EXPECT_EQ(read_file(file), good);

  // Destination is a directory: the final rename fails, the temporary file is removed.
  fs::create_directories(dir / "taken.prt" / "inside");
  EXPECT_THAT(error_of([&] { s.writer().write(dir / "taken.prt"); }), HasSubstr("taken.prt"));
  EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"good.prt", "taken.prt"}));
}

TEST(ArchiveWriter, RefusesBadNamesAndDuplicates) {
  EXPECT_THROW(ArchiveWriter("", 1), ParameterError);
  EXPECT_THROW(ArchiveWriter(std::string(256, 'k'), 1), ParameterError);
  ArchiveWriter w("k", 1);
  w.add_section("a", std::vector<int>{1});
  EXPECT_THROW(w.add_section("a", std::vector<int>{2}), ParameterError);
  EXPECT_THROW(w.add_section("", std::vector<int>{2}), ParameterError);
  EXPECT_THROW(w.add_section(std::string(256, 'n'), std::vector<int>{2}), ParameterError);
  EXPECT_THROW(w.add_meta("", 1), ParameterError);
  EXPECT_TRUE(w.has_section("a"));
  // Overwriting a metadata key replaces it.
  w.add_meta("x", 1).add_meta("x", 2);
  EXPECT_EQ(ArchiveReader::from_bytes(w.to_bytes(), "m").meta().at("x"), 2);
}

TEST(ArchiveWriter, EqualInputsGiveEqualFiles) {
  EXPECT_EQ(Sample().writer().to_bytes(), Sample().writer().to_bytes());
}

TEST(IndexSection, NarrowestTypeRoundTripAndRangeCheck) {
  TempDir dir;
  EXPECT_EQ(index_bytes(1), 1u);
  EXPECT_EQ(index_bytes(256), 1u);
  EXPECT_EQ(index_bytes(257), 2u);
  EXPECT_EQ(index_bytes(65536), 2u);
  EXPECT_EQ(index_bytes(65537), 4u);
  for (std::uint64_t count : {std::uint64_t{3}, std::uint64_t{300}, std::uint64_t{70000}}) {
    const std::vector<std::uint32_t> ids = {0, static_cast<std::uint32_t>(count - 1), 1, 2};
    ArchiveWriter w("ids", 1);
    add_index_section(w, "ids", ids, count);
    // The same ids declared with a smaller count: the last valid one is out of range.
    add_index_section(w, "wide", ids, count);
    const fs::path file = dir / ("ids" + std::to_string(count) + ".prt");
    w.write(file);
    const ArchiveReader r = ArchiveReader::open(file, "ids", 1);
    EXPECT_EQ(read_index_section(r, "ids", 4, count), ids) << count;
    const std::string err = error_of([&] { (void)read_index_section(r, "wide", 4, count - 1); });
    ASSERT_EQ(index_bytes(count - 1), index_bytes(count)) << "the test needs one width";
    EXPECT_THAT(err, ::testing::HasSubstr("out of range")) << count;
    EXPECT_THAT(err, ::testing::HasSubstr(file.string())) << count;
    EXPECT_THAT(error_of([&] { (void)read_index_section(r, "ids", 5, count); }),
                ::testing::Not(::testing::HasSubstr("no exception")));
  }
}

}  // namespace
}  // namespace prt
