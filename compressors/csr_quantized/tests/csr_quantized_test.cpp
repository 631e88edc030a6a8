// Backend `csr_quantized`, beyond the conformance suite: the half decoder against prtlab's
// converter, each value format against its definition computed independently here, the declared
// bound against the measured error (and attained on a crafted row), the Frobenius error against
// a direct computation, save/load, OpenCL against C++, and refusal of corrupt or inconsistent
// files.
#include "csr_quantized/csr_quantized.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "csr_quantized/half_decode.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "support/temp_dir.h"
#include "support/test_light.h"

namespace prt::csr_quantized {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache_root = prt::testing::use_private_cache("csr_quantized");

constexpr ValueFormat kFormats[] = {ValueFormat::kFloat32, ValueFormat::kFloat16, ValueFormat::kU8};

// 7 vertices, M = 9, N = 54 (R = 3), s = 15 (counts up to 225, the most prtlab computes), one
// empty vertex.
TransferMatrix test_transfer(std::uint64_t seed = 5) {
  return random_transfer(seed, RandomTransferSpec{7, 3, 3, 15, 0.7, {4}});
}

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, ValueFormat f) {
  const CubemapLayout cubemap(static_cast<int>(std::lround(std::sqrt(t.cols() / 6.0))));
  const HemisphereGrid grid(static_cast<int>(std::lround(std::sqrt(t.local_count()))));
  return CompressorRegistry::instance()
      .create(std::string(kName), {{"values", std::string(to_string(f))}})
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

const QuantizedCsr& arrays(const CompressedTransfer& ct) {
  return dynamic_cast<const CsrQuantizedTransfer&>(ct).arrays();
}

std::vector<Rgb> test_light(std::size_t n, std::uint64_t seed) {
  return prt::testing::pseudo_random_light(n, seed, 2.0f);
}

// The stored value of entry i as this test reads the format's definition, in double.
double stored_value(const QuantizedCsr& q, std::size_t row, std::size_t i) {
  switch (q.format) {
    case ValueFormat::kFloat32:
      return q.values32[i];
    case ValueFormat::kFloat16:
      return half_to_float(q.values16[i]);
    case ValueFormat::kU8:
      return static_cast<double>(q.codes[i]) * q.row_scales[row];
  }
  return 0;
}

double relative_l2(std::span<const Rgb> a, std::span<const Vec3d> exact) {
  double d2 = 0, n2 = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = static_cast<double>(a[i][c]) - exact[i][c];
      d2 += d * d;
      n2 += exact[i][c] * exact[i][c];
    }
  return std::sqrt(d2 / n2);
}

TEST(CsrQuantized, FiniteHalfDecodeIsPrtlabsConversion) {
  int checked = 0;
  for (std::uint32_t h = 0; h <= 0xffff; ++h) {
    const auto half = static_cast<std::uint16_t>(h);
    if (!is_finite_half(half)) continue;
    const float a = decode_finite_half(half), b = half_to_float(half);
    ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "half 0x" << std::hex << h;
    ++checked;
  }
  EXPECT_EQ(checked, 65536 - 2 * 1024);  // all but the exponent-31 halves (inf, NaN)
  EXPECT_FALSE(is_finite_half(0x7c00));  // +inf
  EXPECT_FALSE(is_finite_half(0xfe00));  // a NaN
}

// Each format stores what its definition says, computed here without the backend's code.
TEST(CsrQuantized, ValuesAreTheFormatsDefinition) {
  const TransferMatrix t = test_transfer();
  ASSERT_GT(t.nnz(), 100u);
  for (ValueFormat f : kFormats) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    const QuantizedCsr& q = arrays(*ct);
    ASSERT_EQ(q.nnz(), t.nnz());
    EXPECT_TRUE(std::equal(q.offsets.begin(), q.offsets.end(), t.row_offsets().begin()));
    EXPECT_TRUE(std::equal(q.columns16.begin(), q.columns16.end(), t.columns16().begin()));
    for (std::size_t row = 0; row < t.rows(); ++row) {
      int cmax = 0;
      for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i)
        cmax = std::max<int>(cmax, t.counts()[i]);
      for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i) {
        const double v = t.counts()[i] / 225.0;
        switch (f) {
          case ValueFormat::kFloat32:
            ASSERT_EQ(q.values32[i], static_cast<float>(v));
            break;
          case ValueFormat::kFloat16:
            ASSERT_EQ(q.values16[i], float_to_half(static_cast<float>(v)));
            break;
          case ValueFormat::kU8: {
            const double scale = cmax / 225.0 / 255.0;
            ASSERT_EQ(q.row_scales[row], static_cast<float>(scale));
            // The nearest code to v / scale = 255 c / cmax, in exact integers: |510 c - 2 q cmax|
            // <= cmax, and a tie (equality) rounds up.
            const long c = t.counts()[i], code = q.codes[i];
            const long twice_off = 510 * c - 2 * code * cmax;
            ASSERT_LE(std::abs(twice_off), cmax) << "entry " << i;
            ASSERT_NE(twice_off, cmax) << "entry " << i << ": a tie rounded down";
            break;
          }
        }
      }
    }
  }
}

TEST(CsrQuantized, StorageFlopsAndBoundPerFormat) {
  const TransferMatrix t = test_transfer();
  const std::uint64_t nnz = t.nnz(), rows = t.rows();
  for (ValueFormat f : kFormats) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    const StorageReport r = ct->storage();
    ASSERT_EQ(r.components.size(), f == ValueFormat::kU8 ? 4u : 3u);
    EXPECT_EQ(r.components[0].name, "row_offsets");
    EXPECT_EQ(r.components[0].bytes, 4 * (rows + 1));
    EXPECT_EQ(r.components[1].name, "columns");
    EXPECT_EQ(r.components[1].bytes, 2 * nnz);
    EXPECT_EQ(r.components[2].name, "values");
    const std::uint64_t value_bytes = f == ValueFormat::kFloat32   ? 4
                                      : f == ValueFormat::kFloat16 ? 2
                                                                   : 1;
    EXPECT_EQ(r.components[2].bytes, value_bytes * nnz);
    if (f == ValueFormat::kU8) {
      EXPECT_EQ(r.components[3].name, "row_scales");
      EXPECT_EQ(r.components[3].bytes, 4 * rows);
    }
    EXPECT_EQ(
        ct->flops_per_relight(),
        2.0 * static_cast<double>(nnz) + (f == ValueFormat::kU8 ? static_cast<double>(rows) : 0.0));
    // rho as defined, from the stored values, here in double.
    const QuantizedCsr& q = arrays(*ct);
    double rho = 0;
    for (std::size_t row = 0; row < t.rows(); ++row)
      for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i) {
        const double v = t.counts()[i] / 225.0;
        rho = std::max(rho, std::abs(stored_value(q, row, i) - v) / v);
      }
    EXPECT_EQ(q.max_entry_error, rho);
    EXPECT_EQ(ct->declared_error_bound(), f == ValueFormat::kFloat32 ? 0.0 : rho);
    if (f == ValueFormat::kFloat32) {
      EXPECT_LE(rho, 0x1p-24);  // float rounding of c / s^2
    } else if (f == ValueFormat::kFloat16) {
      EXPECT_GT(rho, 0.0);
      EXPECT_LE(rho, 0x1p-11);  // half rounding, values well above the subnormals
    } else {
      EXPECT_GT(rho, 0.0);
      // Half a code step over the smallest value (code >= 1): 0.5 / 1 at worst.
      EXPECT_LE(rho, 0.5);
    }
  }
}

// The relight against the exact product in double: within float rounding for float32, within
// the declared bound for the lossy formats, for two non-negative lights.
TEST(CsrQuantized, RelightIsWithinTheDeclaredBound) {
  const TransferMatrix t = test_transfer();
  for (ValueFormat f : kFormats) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    for (std::uint64_t seed : {1u, 2u}) {
      const std::vector<Rgb> light = test_light(t.cols(), seed);
      LocalRadiance out;
      ct->relight({"pixel", light}, out);
      const std::vector<Vec3d> exact = relight_exact_double(t, light);
      const double error = relative_l2(out.values, exact);
      if (f == ValueFormat::kFloat32) {
        EXPECT_LE(error, 1e-6);
      } else {
        EXPECT_LE(error, ct->declared_error_bound() * (1 + 1e-6) + 1e-6);
        EXPECT_GT(error, 0.0);
      }
    }
  }
}

// One vertex, one local cell: every entry is the only one in its column, so a light on that
// column alone shows that entry's relative error as the whole relight's. On the entry that
// attains rho the measured error is the bound.
TEST(CsrQuantized, TheBoundIsAttainedOnACraftedRow) {
  std::vector<std::uint8_t> counts;
  std::vector<std::uint32_t> columns;
  // Counts 1..23 and 225 (s = 15): u8's worst entry is count 1 beside 225 (code 1 for 1.13).
  for (std::uint32_t k = 0; k < 24; ++k) {
    columns.push_back(k);
    counts.push_back(static_cast<std::uint8_t>(k < 23 ? k + 1 : 225));
  }
  const TransferMatrix t = TransferMatrix::from_csr(1, 1, 24, 15, {0, 24}, columns, counts);
  for (ValueFormat f : {ValueFormat::kFloat16, ValueFormat::kU8}) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    const QuantizedCsr& q = arrays(*ct);
    std::size_t worst = 0;
    double rho = 0;
    for (std::size_t i = 0; i < 24; ++i) {
      const double v = counts[i] / 225.0;
      const double e = std::abs(stored_value(q, 0, i) - v) / v;
      if (e > rho) rho = e, worst = i;
    }
    ASSERT_GT(rho, 0.0);
    // u8: count 1 beside 225 gets code 1 for 1.13 (so do counts 2 and 3, for 2.27 and 3.4).
    if (f == ValueFormat::kU8) {
      EXPECT_NEAR(rho, 30.0 / 255.0, 1e-6);
    }
    std::vector<Rgb> light(24, Rgb(0.f));
    light[worst] = Rgb(1.0f, 3.0f, 0.25f);
    LocalRadiance out;
    ct->relight({"pixel", light}, out);
    const double error = relative_l2(out.values, relight_exact_double(t, light));
    EXPECT_LE(error, ct->declared_error_bound() * (1 + 1e-6));
    EXPECT_GE(error, 0.999 * ct->declared_error_bound()) << "the bound is not tight here";
  }
}

TEST(CsrQuantized, FrobeniusErrorIsTheDirectOne) {
  const TransferMatrix t = test_transfer(9);
  for (ValueFormat f : kFormats) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    const QuantizedCsr& q = arrays(*ct);
    double d2 = 0, n2 = 0;
    for (std::size_t row = 0; row < t.rows(); ++row)
      for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i) {
        const double v = t.at(row, t.column(i));
        d2 += (stored_value(q, row, i) - v) * (stored_value(q, row, i) - v);
        n2 += v * v;
      }
    ASSERT_TRUE(ct->expected_frobenius_error().has_value());
    EXPECT_NEAR(*ct->expected_frobenius_error(), std::sqrt(d2 / n2), 1e-12);
  }
}

TEST(CsrQuantized, SaveLoadRoundTripIsExact) {
  const TransferMatrix t = test_transfer();
  prt::testing::TempDir dir("csr_quantized");
  const std::vector<Rgb> light = test_light(t.cols(), 3);
  for (ValueFormat f : kFormats) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    const fs::path file = dir / (std::string(to_string(f)) + ".prt");
    save_compressed(*ct, file);
    const auto loaded = load_compressed(file);
    ASSERT_EQ(loaded->backend(), "csr_quantized");
    const QuantizedCsr &a = arrays(*ct), &b = arrays(*loaded);
    EXPECT_EQ(b.format, f);
    EXPECT_EQ(a.offsets, b.offsets);
    EXPECT_EQ(a.columns16, b.columns16);
    EXPECT_EQ(a.values32, b.values32);
    EXPECT_EQ(a.values16, b.values16);
    EXPECT_EQ(a.codes, b.codes);
    EXPECT_EQ(a.row_scales, b.row_scales);
    EXPECT_EQ(loaded->declared_error_bound(), ct->declared_error_bound());
    EXPECT_EQ(loaded->expected_frobenius_error(), ct->expected_frobenius_error());
    LocalRadiance x, y;
    ct->relight({"pixel", light}, x);
    loaded->relight({"pixel", light}, y);
    ASSERT_EQ(x.values.size(), y.values.size());
    EXPECT_EQ(std::memcmp(x.values.data(), y.values.data(), x.values.size() * sizeof(Rgb)), 0);
  }
}

TEST(CsrQuantized, OpenClMatchesTheCppRelight) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  // N > 65536 (R = 128) takes the u32 column variant.
  for (const TransferMatrix& t :
       {test_transfer(), random_transfer(13, RandomTransferSpec{3, 2, 128, 3, 0.004, {}})}) {
    const std::vector<Rgb> light = test_light(t.cols(), 4);
    for (ValueFormat f : kFormats) {
      SCOPED_TRACE(fmt::format("{}, N = {}", to_string(f), t.cols()));
      const auto ct = compress(t, f);
      auto device = upload_compressed(*ct, *ctx);
      ASSERT_NE(device, nullptr);
      EXPECT_GT(device->device_bytes(), ct->storage().total_bytes());
      LocalRadiance cpp, gpu;
      ct->relight({"pixel", light}, cpp);
      device->relight({"pixel", light}, gpu);
      EXPECT_LE(max_relative_error(gpu, cpp), 1e-5);
    }
  }
}

// Rows of `subset` are `want`'s bit for bit, every other row `other`'s.
::testing::AssertionResult rows_are(const LocalRadiance& out, const LocalRadiance& want,
                                    const LocalRadiance& other,
                                    const std::vector<std::uint32_t>& subset) {
  std::vector<bool> in(out.vertices, false);
  for (const std::uint32_t v : subset) in[v] = true;
  if (out.values.size() != want.values.size() || out.values.size() != other.values.size())
    return ::testing::AssertionFailure() << "sizes differ";
  for (std::size_t r = 0; r < out.values.size(); ++r) {
    const LocalRadiance& ref = in[r / static_cast<std::size_t>(out.dim)] ? want : other;
    if (std::memcmp(&out.values[r], &ref.values[r], sizeof(Rgb)) != 0)
      return ::testing::AssertionFailure()
             << "row " << r << ": " << out.values[r].x << " vs " << ref.values[r].x;
  }
  return ::testing::AssertionSuccess();
}

// Vertices 0, 3, 4 (empty) and 6 (the last): the subset relight writes the full relight's bits
// there and nothing elsewhere; an `out` of the wrong shape comes back zero elsewhere; unsorted,
// repeated or out-of-range vertices are refused.
TEST(CsrQuantized, VertexSubsetRowsAreTheFullRelightsBits) {
  const TransferMatrix t = test_transfer();
  const std::vector<std::uint32_t> subset{0, 3, 4, 6};
  const std::vector<Rgb> light = test_light(t.cols(), 9);
  for (ValueFormat f : kFormats) {
    SCOPED_TRACE(std::string(to_string(f)));
    const auto ct = compress(t, f);
    ASSERT_TRUE(ct->supports_vertex_subset());
    LocalRadiance full;
    ct->relight({"pixel", light}, full);
    LocalRadiance before = full;
    std::fill(before.values.begin(), before.values.end(), Rgb(-7.f));
    LocalRadiance out = before;
    ct->relight_vertices({"pixel", light}, subset, out);
    EXPECT_TRUE(rows_are(out, full, before, subset));
    LocalRadiance fresh;
    ct->relight_vertices({"pixel", light}, subset, fresh);
    LocalRadiance zero = full;
    std::fill(zero.values.begin(), zero.values.end(), Rgb(0.f));
    EXPECT_TRUE(rows_are(fresh, full, zero, subset));
    for (const std::vector<std::uint32_t>& bad :
         {std::vector<std::uint32_t>{3, 1}, std::vector<std::uint32_t>{2, 2},
          std::vector<std::uint32_t>{7}}) {
      EXPECT_THROW(ct->relight_vertices({"pixel", light}, bad, out), ParameterError);
    }
  }
}

// csr_quantized_*_vertices against the C++ subset relight, for each format and both column
// widths; rows outside the subset keep the previous light's values on the device.
TEST(CsrQuantized, OpenClSubsetKernelMatchesTheCppSubset) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  for (const TransferMatrix& t :
       {test_transfer(), random_transfer(13, RandomTransferSpec{3, 2, 128, 3, 0.004, {}})}) {
    const std::vector<std::uint32_t> subset =
        t.vertex_count() == 7 ? std::vector<std::uint32_t>{1, 4, 6} : std::vector<std::uint32_t>{2};
    const std::vector<Rgb> first = test_light(t.cols(), 4), second = test_light(t.cols(), 5);
    for (ValueFormat f : kFormats) {
      SCOPED_TRACE(fmt::format("{}, N = {}", to_string(f), t.cols()));
      const auto ct = compress(t, f);
      auto device = upload_compressed(*ct, *ctx);
      ASSERT_NE(device, nullptr);
      ASSERT_TRUE(device->supports_vertex_subset());
      LocalRadiance before, cpp, gpu;
      device->relight({"pixel", first}, before);
      ct->relight_vertices({"pixel", second}, subset, cpp);
      device->set_vertex_subset(subset);
      EXPECT_GE(device->relight_subset_on_device({"pixel", second}), 0.0);
      gpu = before;
      download(*ctx, device->output_buffer(), std::span<Rgb>(gpu.values), "subset");
      std::vector<bool> in(t.vertex_count(), false);
      for (const std::uint32_t v : subset) in[v] = true;
      const auto m = static_cast<std::size_t>(t.local_count());
      for (std::size_t r = 0; r < gpu.values.size(); ++r) {
        if (in[r / m]) {
          for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(gpu.values[r][c], cpp.values[r][c], 1e-5 * std::abs(cpp.values[r][c]))
                << "row " << r;
        } else {
          EXPECT_EQ(std::memcmp(&gpu.values[r], &before.values[r], sizeof(Rgb)), 0)
              << "row " << r << " outside the subset changed";
        }
      }
      EXPECT_THROW(device->set_vertex_subset(std::vector<std::uint32_t>{2, 1}), ParameterError);
    }
  }
}

// A byte flipped or cut off is caught by the archive's checksum; a well-formed archive whose
// arrays a kernel would trust wrongly is caught by load. Both name the file.
TEST(CsrQuantized, CorruptTruncatedOrInconsistentFilesAreInputErrors) {
  const TransferMatrix t = test_transfer();
  prt::testing::TempDir dir("csr_quantized_bad");
  const fs::path file = dir / "t.prt";
  save_compressed(*compress(t, ValueFormat::kFloat16), file);
  std::string bytes = [&] {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  auto write_bytes = [&](const std::string& b) {
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(b.data(), b.size());
  };
  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x10;
  write_bytes(flipped);
  EXPECT_THROW(load_compressed(file), InputError);
  write_bytes(bytes.substr(0, bytes.size() - 100));
  EXPECT_THROW(load_compressed(file), InputError);

  auto write_archive = [&](std::vector<std::uint16_t> columns, std::vector<std::uint16_t> values,
                           int version) {
    ArchiveWriter w("compressed-transfer", 1);
    w.add_meta("backend", "csr_quantized");
    w.add_meta("flops_per_relight", 4.0);
    w.add_meta("storage_bytes", 1);
    w.add_meta("csr_quantized_version", version);
    w.add_meta("vertices", 1);
    w.add_meta("local_count", 1);
    w.add_meta("pixel_count", 24);
    w.add_meta("values", "float16");
    w.add_meta("max_entry_error", 0.0);
    w.add_meta("frobenius_error", 0.0);
    w.add_section("row_offsets", std::vector<std::uint32_t>{0, 2});
    w.add_section("columns", std::move(columns));
    w.add_section("values", std::move(values));
    w.write(file);
  };
  write_archive({3, 7}, {0x3c00, 0x3800}, kStateVersion);
  EXPECT_NO_THROW(load_compressed(file));
  for (const auto& [what, columns, values, version] : std::vector<
           std::tuple<std::string, std::vector<std::uint16_t>, std::vector<std::uint16_t>, int>>{
           {"column 24 >= N", {3, 24}, {0x3c00, 0x3800}, kStateVersion},
           {"a NaN half", {3, 7}, {0x7e00, 0x3800}, kStateVersion},
           {"one value short", {3, 7}, {0x3c00}, kStateVersion},
           {"a newer version", {3, 7}, {0x3c00, 0x3800}, kStateVersion + 1}}) {
    SCOPED_TRACE(what);
    write_archive(columns, values, version);
    try {
      load_compressed(file);
      ADD_FAILURE() << "loaded";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), file);
    }
  }
}

TEST(CsrQuantized, AnUnknownFormatIsAParameterError) {
  EXPECT_THROW(CompressorRegistry::instance().create("csr_quantized", {{"values", "bf16"}}),
               ParameterError);
  EXPECT_THROW(value_format_from("int4"), ParameterError);
  for (ValueFormat f : kFormats) EXPECT_EQ(value_format_from(to_string(f)), f);
}

}  // namespace
}  // namespace prt::csr_quantized
