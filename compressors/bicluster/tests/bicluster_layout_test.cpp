// Backend `bicluster`, stored layout (bicluster.h): SELL-4 slices in phase 2's row order with
// u16 id deltas and zero slots. With more than 2^16 biclusters a lane must cross gaps through zero
// slots and pad on the slot above its last id; the arrays must still stand for exactly the packed
// biclusters, relight them (C++ and OpenCL), survive save/load, and the loader must refuse
// inconsistent arrays.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "bicluster/bicluster.h"
#include "prtlab/base/error.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::bicluster {
namespace {

namespace fs = std::filesystem;

struct Fixture {
  TransferMatrix t;
  Biclustering b;
};

// Every entry of a random T as a 1x1 term (~80,000 of them, so ids pass 2^16), biclusters of
// three consecutive rows over all rows but the last, and one of two rows joining row 0 to the
// last row. Phase 2's order places the triples' rows first (larger biclusters first), so the
// pair's id is numbered with row 0, near the start, and the last row comes after every other
// row: its lane goes from that small id to its terms' ids above 2^16.
Fixture many_biclusters() {
  Fixture f;
  f.t = random_transfer(3, RandomTransferSpec{300, 4, 8, 2, 0.7, {}});
  const SparseCounts c = counts_of(f.t);
  f.b.rows = c.rows;
  f.b.cols = c.cols;
  for (std::size_t j = 0; j < c.rows; ++j)
    for (std::uint32_t i = c.offsets[j]; i < c.offsets[j + 1]; ++i)
      f.b.residual.push_back({static_cast<std::uint32_t>(j), c.columns[i], c.values[i]});
  const auto last = static_cast<std::uint32_t>(c.rows - 1);
  for (std::uint32_t j = 0; j + 2 < last; j += 3)
    f.b.biclusters.push_back(Bicluster{{j, j + 1, j + 2}, {j % 97}, {3}});
  f.b.biclusters.push_back(Bicluster{{0, last}, {5, 14}, {2, -1}});
  return f;
}

TEST(BiclusterLayout, ZeroSlotsCarryLanesAcrossLargeGaps) {
  const Fixture f = many_biclusters();
  const BiclusterArrays a = pack(f.b, f.t);
  ASSERT_GT(a.bicluster_count(), 2u * kZeroStride);
  EXPECT_EQ(reconstruct(a), f.b.reconstruct());
  for (std::size_t i = 0; i < a.bicluster_count(); i += kZeroStride)
    EXPECT_EQ(a.bic_col_offsets[i + 1], a.bic_col_offsets[i]) << "zero slot " << i;
  EXPECT_EQ(a.real_bicluster_count(), f.b.biclusters.size() + f.b.residual.size());
  // Some lane stepped on a zero slot in the middle of its ids (a gap above 2^16).
  bool crossed = false;
  for (std::size_t s = 0; s < a.slice_count() && !crossed; ++s) {
    for (int lane = 0; lane < kSliceRows; ++lane) {
      std::uint32_t id = a.slice_base[s];
      bool zero_seen = false;
      for (std::uint32_t q = a.slice_offsets[s] + lane; q < a.slice_offsets[s + 1];
           q += kSliceRows) {
        id += a.slice_codes[q];
        if (id % kZeroStride == 0) {
          zero_seen = true;
        } else if (zero_seen) {
          crossed = true;
        }
        EXPECT_LT(id, a.product_count());
      }
    }
  }
  EXPECT_TRUE(crossed) << "the fixture should force a lane through a zero slot";

  // FLOPs: sum W over the packed biclusters (1x1 terms 2 each).
  std::int64_t flops = 2 * static_cast<std::int64_t>(f.b.residual.size());
  for (const auto& bc : f.b.biclusters) flops += bc.cost();
  const BiclusterTransfer ct(a);
  EXPECT_EQ(ct.flops_per_relight(), static_cast<double>(flops));

  // Relight against the double product of the packed counts.
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  LightCoeffs light{"pixel", std::vector<Rgb>(f.t.cols())};
  for (Rgb& v : light.values) v = Rgb(u(rng), u(rng), u(rng));
  const SparseCounts packed = f.b.reconstruct();
  LocalRadiance out;
  ct.relight(light, out);
  double largest = 0, worst = 0;
  std::vector<Vec3d> exact(packed.rows, Vec3d(0.0));
  for (std::size_t j = 0; j < packed.rows; ++j) {
    for (std::uint32_t i = packed.offsets[j]; i < packed.offsets[j + 1]; ++i)
      exact[j] += packed.values[i] * a.scale() * Vec3d(light.values[packed.columns[i]]);
    for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(exact[j][c]));
  }
  for (std::size_t j = 0; j < packed.rows; ++j)
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(out.values[j][c] - exact[j][c]));
  EXPECT_LT(worst, 1e-6 * largest);

  if (ClContext* ctx = default_context()) {
    // Both phase-2 kernels, whatever `auto` picks on this device: u16 deltas decoded on the
    // device (the zero slots above carry lanes across gaps of more than 2^16) and u32 ids
    // expanded at upload.
    for (const DeviceIds ids : {DeviceIds::kU16, DeviceIds::kU32}) {
      auto device = upload_arrays(*ctx, a, ids);
      LocalRadiance gpu;
      device->relight(light, gpu);
      ASSERT_EQ(gpu.values.size(), out.values.size());
      double diff = 0;
      for (std::size_t j = 0; j < packed.rows; ++j)
        for (int c = 0; c < 3; ++c)
          diff = std::max(diff, static_cast<double>(std::abs(gpu.values[j][c] - out.values[j][c])));
      EXPECT_LT(diff, 1e-5 * largest)
          << "OpenCL (" << to_string(ids) << ") vs C++ on " << ctx->info().label();
    }
  }
}

TEST(BiclusterLayout, SlicesHoldRowsSortedByLengthWithLittlePadding) {
  const TransferMatrix t = random_transfer(12, RandomTransferSpec{40, 4, 4, 2, 0.6, {}});
  const auto ct =
      CompressorRegistry::instance()
          .create("bicluster", {{"seed", "2"}})
          ->compress({t, nullptr, CubemapLayout(4), HemisphereGrid(4)}, Progress::null());
  const BiclusterArrays& a = dynamic_cast<const BiclusterTransfer&>(*ct).arrays();
  EXPECT_EQ(reconstruct(a), counts_of(t));
  EXPECT_EQ(a.slice_count(), t.vertex_count() * 4);  // M = 16: four slices of four rows per vertex
  // Within a window of kRowWindow rows of phase 2's order, longer rows first.
  std::size_t previous_longest = 0;
  for (std::size_t s = 0; s < a.slice_count(); ++s) {
    std::size_t lengths[kSliceRows] = {};
    for (int lane = 0; lane < kSliceRows; ++lane)
      a.for_each_id(s, lane, [&](std::uint32_t) { ++lengths[lane]; });
    for (int lane = 1; lane < kSliceRows; ++lane)
      EXPECT_GE(lengths[lane - 1], lengths[lane]) << "slice " << s << " lane " << lane;
    if (s % (kRowWindow / kSliceRows) != 0) {
      EXPECT_LE(lengths[0], previous_longest) << "slice " << s << " of its window";
    }
    previous_longest = lengths[kSliceRows - 1];
  }
  const double padding = 1.0 - static_cast<double>(a.incidences()) / a.slice_codes.size();
  EXPECT_LT(padding, 0.25) << "padding share of the slice codes";
}

// Phase 2's row order puts the rows of the largest bicluster first (they gather the same
// product), up to the length sort within windows of kRowWindow rows.
TEST(BiclusterLayout, RowOrderPlacesTheLargestBiclustersRowsTogether) {
  Fixture f = many_biclusters();
  const auto rows = static_cast<std::uint32_t>(f.b.rows);
  // Spread over the whole matrix: in row order they would span all slices.
  const Bicluster largest{{7, rows / 5, rows / 3, rows / 2, rows - 9, rows - 2}, {3}, {1}};
  f.b.biclusters.push_back(largest);
  const BiclusterArrays a = pack(f.b, f.t);
  EXPECT_EQ(reconstruct(a), f.b.reconstruct());
  ASSERT_GT(f.b.rows, 4 * kRowWindow);
  std::vector<std::uint32_t> first;  // the rows of the first window
  for (std::size_t q = 0; q < kRowWindow; ++q) first.push_back(a.slice_rows[q]);
  for (std::uint32_t row : largest.rows)
    EXPECT_NE(std::find(first.begin(), first.end(), row), first.end())
        << "row " << row << " of the largest bicluster is not in the first window";
}

std::unique_ptr<CompressedTransfer> save_and_load(const BiclusterArrays& a) {
  const fs::path path =
      fs::temp_directory_path() / ("bicluster_layout_" + std::to_string(::getpid()) + ".prt");
  save_compressed(BiclusterTransfer(a), path);
  struct Remove {
    fs::path p;
    ~Remove() { fs::remove(p); }
  } remove{path};
  return load_compressed(path);
}

TEST(BiclusterLayout, SaveLoadKeepsTheArraysAndTheLoaderRefusesInconsistentOnes) {
  const Fixture f = many_biclusters();
  BiclusterArrays a = pack(f.b, f.t);
  // The fixture's biclusters come on top of every entry of T, so its sum is not a matrix of
  // sample counts: saved as lossy, only the structural checks below apply to it.
  a.error = a.bound = 0.5;
  const auto loaded = save_and_load(a);
  const BiclusterArrays& l = dynamic_cast<const BiclusterTransfer&>(*loaded).arrays();
  EXPECT_EQ(l.bic_col_offsets, a.bic_col_offsets);
  EXPECT_EQ(l.bic_columns, a.bic_columns);
  EXPECT_EQ(l.bic_constants, a.bic_constants);
  EXPECT_EQ(l.slice_offsets, a.slice_offsets);
  EXPECT_EQ(l.slice_rows, a.slice_rows);
  EXPECT_EQ(l.slice_base, a.slice_base);
  EXPECT_EQ(l.slice_codes, a.slice_codes);

  BiclusterArrays beyond = a;  // a lane reading past the last bicluster
  const auto nb = static_cast<std::uint32_t>(a.bicluster_count());
  beyond.slice_base.back() = nb;
  beyond.slice_codes[beyond.slice_offsets[beyond.slice_count() - 1]] =
      (nb + 1) % kZeroStride ? 1 : 2;
  EXPECT_THROW(save_and_load(beyond), InputError);

  BiclusterArrays twice = a;  // a row listed in two lanes, another in none
  twice.slice_rows[1] = twice.slice_rows[0];
  EXPECT_THROW(save_and_load(twice), InputError);

  // vertices x M wraps around size_t to the true row count, so every section still matches:
  // only the shape check can refuse it.
  BiclusterArrays wrapped = a;
  ASSERT_EQ(a.local_count, 16);
  wrapped.vertices += std::size_t{1} << 60;
  ASSERT_EQ(wrapped.rows(), a.rows());
  EXPECT_THROW(save_and_load(wrapped), InputError);

  BiclusterArrays slot = a;  // zero slot 0 takes bicluster 1's columns
  slot.bic_col_offsets[1] = slot.bic_col_offsets[2];
  EXPECT_THROW(save_and_load(slot), InputError);
}

// A damaged archive with valid checksums: the arrays are changed and then saved, so only the
// lossless loader's own checks can refuse them; and a result that does not reproduce T, built
// in memory where no loader sees it, is an error of the evaluation, not a reported number.
TEST(BiclusterLayout, ALosslessArchiveThatIsNotTsCountsIsRefused) {
  const TransferMatrix t = random_transfer(5, RandomTransferSpec{60, 4, 4, 2, 0.6, {}});
  const auto ct =
      CompressorRegistry::instance()
          .create("bicluster", {{"seed", "2"}})
          ->compress({t, nullptr, CubemapLayout(4), HemisphereGrid(4)}, Progress::null());
  const BiclusterArrays& a = dynamic_cast<const BiclusterTransfer&>(*ct).arrays();
  ASSERT_EQ(a.bound, 0.0);
  ASSERT_NO_THROW(save_and_load(a));
  std::size_t wide = 0;  // a bicluster with two columns or more
  while (wide < a.bicluster_count() && a.bic_col_offsets[wide + 1] - a.bic_col_offsets[wide] < 2)
    ++wide;
  ASSERT_LT(wide, a.bicluster_count()) << "the search found no bicluster of two columns";
  const std::uint32_t q = a.bic_col_offsets[wide];

  auto refused = [](const BiclusterArrays& damaged, const std::string& needle) {
    try {
      save_and_load(damaged);
      return ::testing::AssertionFailure() << "loaded";
    } catch (const InputError& e) {
      if (std::string(e.what()).find(needle) == std::string::npos)
        return ::testing::AssertionFailure() << e.what();
      return ::testing::AssertionSuccess();
    }
  };
  BiclusterArrays swapped = a;
  std::swap(swapped.bic_columns[q], swapped.bic_columns[q + 1]);
  EXPECT_TRUE(refused(swapped, "not increasing"));

  BiclusterArrays extreme = a;
  extreme.bic_constants[q] = 30000;
  EXPECT_TRUE(refused(extreme, "not a lossless transfer"));

  BiclusterArrays negative = a;
  negative.bic_constants[q] = static_cast<std::int16_t>(-negative.bic_constants[q] - 8);
  EXPECT_TRUE(refused(negative, "not a lossless transfer"));

  BiclusterArrays zero = a;
  zero.bic_constants[q] = 0;
  EXPECT_TRUE(refused(zero, "constant 0"));

  // In memory (no loader): the evaluation measures it against T and refuses to report it.
  const BiclusterTransfer wrong(extreme);
  const std::vector<EvaluationLight> lights = {
      {"sunsky", evaluation_lights(4, 1).front().radiance}};
  EXPECT_THROW((void)evaluate_backend(wrong, t, lights, nullptr, {.repeats = 1}), NumericalError);
  EXPECT_NO_THROW((void)evaluate_backend(*ct, t, lights, nullptr, {.repeats = 1}));
}

}  // namespace
}  // namespace prt::bicluster
