// quantized8: an out-of-tree prtlab compressor, built as a plugin against an installed (or a
// build-tree) prtlab. It is the template of docs/adding-a-compressor.md: copy this folder, rename
// the backend, replace the method. Everything a backend needs is in this one file: parameters,
// compression, storage accounting, FLOP count, error bound, C++ relight, OpenCL relight (kernel
// source embedded below), save/load, and the one registration line at the bottom, the same
// PRT_REGISTER_COMPRESSOR an in-tree backend ends with.
//
// Method. The exact transfer T stores every entry as a visibility count c in 1..s^2 with the
// common scale 1/s^2 (transfer_matrix.h). quantized8 keeps T's sparsity (CSR; u16 column
// indices, or u32 when N > 65536) and stores each entry as a u8 code times a per-row step:
//
//   Q = 2^bits - 1 levels, cmax = the row's largest count
//   cmax <= Q:  code = c, step = 1/s^2                          (exact)
//   cmax >  Q:  code = round(c Q / cmax), step = cmax / (Q s^2)  (entries with code 0 are dropped)
//
// With bits = 8 every T prtlab computes (s <= 15) is stored exactly. Fewer bits trade accuracy
// for fewer entries (and so fewer bytes and FLOPs) wherever a row's counts exceed the levels,
// e.g. bits = 1 keeps only the entries of at least half the row's largest, all at that value.
//
// Error bound. For an entry of exact value v stored as v', let rho = max |v' - v| / v over all
// entries (a dropped entry has rho = 1). For any light with non-negative channels,
//   |(T' L - T L)_i| <= sum_k |v'_ik - v_ik| L_k <= rho sum_k v_ik L_k = rho (T L)_i
// per row and channel, hence ||T' L - T L||_2 <= rho ||T L||_2: rho is the relative L2 bound
// declared (0 when nothing was rounded), computed exactly at compression time and saved.
#include <prtlab/base/error.h>
#include <prtlab/compress/compressor.h>
#include <prtlab/compress/compressor_registry.h>
#include <prtlab/opencl/cl_runtime.h>
#include <prtlab/storage/archive.h>
#include <prtlab/transfer/transfer_matrix.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace quantized8 {
namespace {

constexpr const char* kName = "quantized8";
// Bumped when the saved sections or their meaning change; load() refuses other versions.
constexpr int kFormatVersion = 1;
constexpr std::size_t kWorkGroup = 64;

// The OpenCL kernel. A plugin cannot add files to prtlab's kernels/ folder, so it carries its
// source and builds it with prt::build_program_source(), which prepends prtlab's prelude
// (PRT_GUARD, prt_store_rgb3, PRT_WG_SIZE) and caches the program like any built-in kernel.
// One work-item per row; two independent accumulators, in the same order as relight_rows() so
// that both paths agree to float rounding. Q8_COLUMN (ushort or uint) is set by the host.
constexpr std::string_view kKernelSource = R"CLC(
__kernel void quantized8_relight(const uint rows, __global const uint* offsets,
                                 __global const Q8_COLUMN* columns, __global const uchar* codes,
                                 __global const float* row_step, __global const float4* light,
                                 __global float* out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  const uint end = offsets[row + 1];
  uint k = offsets[row];
  float4 acc0 = (float4)(0.0f);
  float4 acc1 = (float4)(0.0f);
  for (; k + 1 < end; k += 2) {
    acc0 += (float)codes[k] * light[columns[k]];
    acc1 += (float)codes[k + 1] * light[columns[k + 1]];
  }
  if (k < end) acc0 += (float)codes[k] * light[columns[k]];
  prt_store_rgb3(out, row, row_step[row] * (acc0 + acc1));
}
)CLC";

/// The compressed arrays, shared by the C++ and the OpenCL paths.
struct Arrays {
  std::size_t vertices = 0;
  int local_count = 0;  // M
  int pixel_count = 0;  // N
  int bits = 8;
  double error_bound = 0;                // rho of the header comment
  std::vector<std::uint32_t> offsets;    // rows + 1
  std::vector<std::uint16_t> columns16;  // nnz, when N <= 65536
  std::vector<std::uint32_t> columns32;  // nnz, when N > 65536
  std::vector<std::uint8_t> codes;       // nnz
  std::vector<float> row_step;           // rows

  std::size_t rows() const { return row_step.size(); }
  std::size_t nnz() const { return codes.size(); }
  bool wide() const { return pixel_count > 65536; }
  std::size_t column_bytes() const { return wide() ? 4 : 2; }
};

void check_light(const prt::LightCoeffs& light, int pixel_count) {
  prt::check_pixel_light(light, static_cast<std::size_t>(pixel_count), kName);
}

/// out[row] = step[row] * sum code * light[column], for rows [begin, end).
template <typename Column>
void relight_rows(const Arrays& a, std::span<const Column> columns, std::span<const prt::Rgb> light,
                  std::span<prt::Rgb> out, std::size_t begin, std::size_t end) {
  for (std::size_t row = begin; row < end; ++row) {
    prt::Rgb acc0(0.f);
    prt::Rgb acc1(0.f);
    std::uint32_t k = a.offsets[row];
    const std::uint32_t stop = a.offsets[row + 1];
    for (; k + 1 < stop; k += 2) {
      acc0 += static_cast<float>(a.codes[k]) * light[columns[k]];
      acc1 += static_cast<float>(a.codes[k + 1]) * light[columns[k + 1]];
    }
    if (k < stop) acc0 += static_cast<float>(a.codes[k]) * light[columns[k]];
    out[row] = a.row_step[row] * (acc0 + acc1);
  }
}

/// The arrays on an OpenCL device. Holds a reference to the context: it must not outlive it.
class Quantized8Device final : public prt::DeviceRelighter {
 public:
  Quantized8Device(prt::ClContext& ctx, const Arrays& a)
      : ctx_(ctx),
        pixel_count_(a.pixel_count),
        rows_(a.rows()),
        local_count_(a.local_count),
        vertices_(a.vertices),
        light_host_(static_cast<std::size_t>(a.pixel_count)),
        out_host_(a.rows() * 3) {
    const auto defines = prt::KernelDefines()
                             .set("PRT_WG_SIZE", kWorkGroup)
                             .set("Q8_COLUMN", a.wide() ? "uint" : "ushort");
    const cl::Program program =
        prt::build_program_source(ctx, "quantized8.cl", kKernelSource, defines);
    kernel_ = prt::make_kernel(program, "quantized8_relight");
    offsets_ =
        prt::upload(ctx, std::span<const std::uint32_t>(a.offsets), "quantized8 row offsets");
    columns_ =
        a.wide()
            ? prt::upload(ctx, std::span<const std::uint32_t>(a.columns32), "quantized8 columns")
            : prt::upload(ctx, std::span<const std::uint16_t>(a.columns16), "quantized8 columns");
    codes_ = prt::upload(ctx, std::span<const std::uint8_t>(a.codes), "quantized8 codes");
    steps_ = prt::upload(ctx, std::span<const float>(a.row_step), "quantized8 row steps");
    light_ = prt::make_buffer(ctx, light_host_.size() * sizeof(cl_float4), CL_MEM_READ_ONLY,
                              "quantized8 light");
    out_ = prt::make_buffer(ctx, out_host_.size() * sizeof(float), CL_MEM_WRITE_ONLY,
                            "quantized8 local radiance");
    device_bytes_ = prt::buffer_bytes({&offsets_, &columns_, &codes_, &steps_, &light_, &out_});
    prt::set_args(kernel_, static_cast<cl_uint>(rows_), offsets_, columns_, codes_, steps_, light_,
                  out_);
  }

  double relight_on_device(const prt::LightCoeffs& light) override {
    check_light(light, pixel_count_);
    // RGB travels as float4 (prelude.cl): aligned loads the device can vectorise.
    prt::upload_light(ctx_, light_, light.values, light_host_, "quantized8 light");
    if (rows_ == 0) return 0.0;  // OpenCL forbids an empty launch
    cl::Event done = prt::launch(ctx_, "quantized8.relight", kernel_,
                                 prt::LaunchRange::linear(rows_, kWorkGroup));
    done.wait();
    const auto start = done.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    const auto end = done.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    return static_cast<double>(end - start) * 1e-6;
  }

  double relight(const prt::LightCoeffs& light, prt::LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    prt::download(ctx_, out_, std::span<float>(out_host_), "quantized8 local radiance");
    out = prt::LocalRadiance(prt::RadianceBasis::kPixel, local_count_, vertices_);
    for (std::size_t row = 0; row < rows_; ++row)
      out.values[row] =
          prt::Rgb(out_host_[3 * row], out_host_[3 * row + 1], out_host_[3 * row + 2]);
    return ms;
  }

  std::uint64_t device_bytes() const override { return device_bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  prt::ClContext& ctx_;
  int pixel_count_;
  std::size_t rows_;
  int local_count_;
  std::size_t vertices_;
  std::vector<cl_float4> light_host_;
  std::vector<float> out_host_;
  cl::Kernel kernel_;
  cl::Buffer offsets_, columns_, codes_, steps_, light_, out_;
  std::uint64_t device_bytes_ = 0;
};

class Quantized8Transfer final : public prt::CompressedTransfer {
 public:
  explicit Quantized8Transfer(Arrays arrays) : a_(std::move(arrays)) {}

  std::string backend() const override { return kName; }

  prt::StorageReport storage() const override {
    return {{
        {"row_offsets", a_.offsets.size() * sizeof(std::uint32_t),
         "u32 per row + 1: index of the row's first entry"},
        {"columns", a_.nnz() * a_.column_bytes(),
         a_.wide() ? "u32 cubemap pixel index per entry" : "u16 cubemap pixel index per entry"},
        {"codes", a_.nnz() * sizeof(std::uint8_t), "u8 per entry: value = code * row step"},
        {"row_step", a_.rows() * sizeof(float), "f32 per row: the value of code 1"},
    }};
  }

  // One multiply-add per stored entry, as the papers count T L (2 nnz). The per-row step is a
  // multiply per row that the exact product has too (its 1/s^2) and is not counted either.
  double flops_per_relight() const override { return 2.0 * static_cast<double>(a_.nnz()); }

  double declared_error_bound() const override { return a_.error_bound; }

  prt::LightCoeffs project_light(const prt::Cubemap& radiance) const override {
    if (radiance.layout.pixel_count() != a_.pixel_count)
      throw prt::ParameterError(fmt::format("{}: light cubemap has {} pixels, the transfer {}",
                                            kName, radiance.layout.pixel_count(), a_.pixel_count));
    return {"pixel", radiance.light_vector()};
  }

  void relight(const prt::LightCoeffs& light, prt::LocalRadiance& out) const override {
    check_light(light, a_.pixel_count);
    out = prt::LocalRadiance(prt::RadianceBasis::kPixel, a_.local_count, a_.vertices);
    // Rows are independent: TBB splits them over the cores (prtlab's own loops use TBB too).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a_.rows(), 1024), [&](const auto& r) {
      if (a_.wide())
        relight_rows<std::uint32_t>(a_, a_.columns32, light.values, out.values, r.begin(), r.end());
      else
        relight_rows<std::uint16_t>(a_, a_.columns16, light.values, out.values, r.begin(), r.end());
    });
  }

  // quantized8 declares no device options (CompressorEntry::device_params), so the set is empty.
  std::unique_ptr<prt::DeviceRelighter> upload(prt::ClContext& context,
                                               const prt::ParamSet&) const override {
    return std::make_unique<Quantized8Device>(context, a_);
  }

  void save(prt::ArchiveWriter& w) const override {
    w.add_meta("quantized8", {{"format_version", kFormatVersion},
                              {"vertices", a_.vertices},
                              {"local_count", a_.local_count},
                              {"pixel_count", a_.pixel_count},
                              {"bits", a_.bits},
                              {"error_bound", a_.error_bound}});
    w.add_section("row_offsets", a_.offsets);
    if (a_.wide())
      w.add_section("columns", a_.columns32);
    else
      w.add_section("columns", a_.columns16);
    w.add_section("codes", a_.codes);
    w.add_section("row_step", a_.row_step);
  }

  static std::unique_ptr<prt::CompressedTransfer> load(const prt::ArchiveReader& r) {
    const auto meta = r.meta_value<nlohmann::json>("quantized8");
    const auto fail = [&](const std::string& problem) {
      return prt::InputError(r.path(), fmt::format("{}: {}", kName, problem));
    };
    Arrays a;
    try {
      if (meta.at("format_version").get<int>() != kFormatVersion)
        throw fail(fmt::format("format version {} is not {}", meta.at("format_version").dump(),
                               kFormatVersion));
      a.vertices = meta.at("vertices").get<std::size_t>();
      a.local_count = meta.at("local_count").get<int>();
      a.pixel_count = meta.at("pixel_count").get<int>();
      a.bits = meta.at("bits").get<int>();
      a.error_bound = meta.at("error_bound").get<double>();
    } catch (const nlohmann::json::exception& e) {
      throw fail(fmt::format("bad metadata ({})", e.what()));
    }
    if (a.local_count <= 0 || a.pixel_count <= 0 || a.bits < 1 || a.bits > 8)
      throw fail(fmt::format("bad shape or bits: M = {}, N = {}, bits = {}", a.local_count,
                             a.pixel_count, a.bits));
    const std::uint64_t rows = a.vertices * static_cast<std::uint64_t>(a.local_count);
    a.offsets = r.section<std::uint32_t>("row_offsets", rows + 1);
    a.row_step = r.section<float>("row_step", rows);
    const std::uint64_t nnz = a.offsets.back();
    if (a.wide())
      a.columns32 = r.section<std::uint32_t>("columns", nnz);
    else
      a.columns16 = r.section<std::uint16_t>("columns", nnz);
    a.codes = r.section<std::uint8_t>("codes", nnz);
    // The kernel trusts these arrays, so a file that passed the checksum but was written wrong
    // must still not make it read out of bounds.
    if (a.offsets.front() != 0 || !std::is_sorted(a.offsets.begin(), a.offsets.end()))
      throw fail("row offsets are not non-decreasing from 0");
    const auto out_of_range = [&](std::uint32_t c) { return c >= std::uint32_t(a.pixel_count); };
    if (std::any_of(a.columns16.begin(), a.columns16.end(), out_of_range) ||
        std::any_of(a.columns32.begin(), a.columns32.end(), out_of_range))
      throw fail(fmt::format("a column index is out of range (N = {})", a.pixel_count));
    return std::make_unique<Quantized8Transfer>(std::move(a));
  }

 private:
  Arrays a_;
};

class Quantized8Compressor final : public prt::Compressor {
 public:
  explicit Quantized8Compressor(int bits) : bits_(bits) {}

  std::unique_ptr<prt::CompressedTransfer> compress(const prt::TransferInput& input,
                                                    prt::Progress& progress) const override {
    prt::check_transfer_shape(input, kName);
    const prt::TransferMatrix& t = input.transfer;
    Arrays a;
    a.vertices = t.vertex_count();
    a.local_count = t.local_count();
    a.pixel_count = static_cast<int>(t.cols());
    a.bits = bits_;
    const int levels = (1 << bits_) - 1;
    const auto offsets = t.row_offsets();
    const auto counts = t.counts();
    a.offsets.reserve(t.rows() + 1);
    a.offsets.push_back(0);
    a.row_step.reserve(t.rows());
    a.codes.reserve(t.nnz());
    double rho = 0;
    for (std::size_t row = 0; row < t.rows(); ++row) {
      const auto begin = counts.begin() + offsets[row];
      const auto end = counts.begin() + offsets[row + 1];
      const int cmax = begin == end ? 0 : *std::max_element(begin, end);
      const bool exact = cmax <= levels;
      a.row_step.push_back(static_cast<float>(exact ? t.scale() : t.scale() * cmax / levels));
      for (std::uint32_t k = offsets[row]; k < offsets[row + 1]; ++k) {
        const int c = counts[k];
        // Integer round-to-nearest of c * levels / cmax (halves round up).
        const int code = exact ? c : (2 * c * levels + cmax) / (2 * cmax);
        if (!exact) {
          const double stored = static_cast<double>(code) * cmax / levels;
          rho = std::max(rho, std::abs(stored - c) / c);
        }
        if (code == 0) continue;
        if (a.wide())
          a.columns32.push_back(t.column(k));
        else
          a.columns16.push_back(static_cast<std::uint16_t>(t.column(k)));
        a.codes.push_back(static_cast<std::uint8_t>(code));
      }
      a.offsets.push_back(static_cast<std::uint32_t>(a.codes.size()));
      if ((row + 1) % 4096 == 0) progress.advance(4096);
    }
    progress.finish();
    a.error_bound = rho;
    return std::make_unique<Quantized8Transfer>(std::move(a));
  }

 private:
  int bits_;
};

prt::CompressorEntry entry() {
  prt::CompressorEntry e;
  e.name = kName;
  e.description =
      "example plugin (examples/plugin-template): CSR with a u8 code per entry and an f32 step "
      "per row; exact with bits=8, lossy with fewer bits";
  e.params = {{.key = "bits",
               .type = prt::ParamType::kInt,
               .default_value = "8",
               .min = 1.0,
               .max = 8.0,
               .choices = {},
               .doc = "quantisation levels per row: 2^bits - 1; rows whose counts fit are stored "
                      "exactly, others are rounded (entries rounding to 0 are dropped)"}};
  // More bits drop fewer entries (an entry is dropped when 2 c levels < cmax).
  e.size_knob =
      prt::SizeKnob{.key = "bits", .direction = prt::SizeKnob::Direction::kLargerIsMoreStorage};
  e.lossless = false;  // bits < 8 may round; declared_error_bound() says how much
  e.create = [](const prt::ParamSet& p) {
    return std::make_unique<Quantized8Compressor>(static_cast<int>(p.get_int("bits")));
  };
  e.load = &Quantized8Transfer::load;
  return e;
}

}  // namespace
}  // namespace quantized8

// The line every backend ends with. When prtlab opens this library (--plugin), the registrar
// runs and adds the entry to the registry of the prtlab that loads it (libprtlab_core.so is
// shared). It carries the plugin API version of the headers this file was compiled with:
// prtlab refuses the plugin, before calling entry(), when that differs from its own.
PRT_REGISTER_COMPRESSOR(quantized8::entry);
