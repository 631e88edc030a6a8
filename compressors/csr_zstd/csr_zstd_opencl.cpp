// The OpenCL relight of backend `csr_zstd` (compressors/csr_zstd/csr_zstd.cl). A device cannot
// run zstd, so every relight decompresses the frames on the host (TBB over frames), uploads the
// CSR arrays and runs the kernel. relight_on_device() therefore returns the wall time of all
// three, not the kernel time alone: the kernel alone is `uncompressed`'s kernel, and the point of
// this baseline is what keeping T compressed costs per relight. A vertex subset relight does the
// same for the frames holding the subset's rows only (decompress them, upload the arrays' span
// from the first to the last of them, run csr_zstd_vertices over the subset's rows).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstring>
#include <limits>

#include "csr_zstd/csr_zstd.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_id_list.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::csr_zstd {
namespace {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

// One work-item per row, 64 per group, as uncompressed's rows variant.
constexpr std::size_t kWorkGroup = 64;

class CsrZstdDevice final : public DeviceRelighter {
 public:
  CsrZstdDevice(ClContext& ctx, std::shared_ptr<const FramedCsr> csr)
      : ctx_(ctx),
        csr_(std::move(csr)),
        rows_(csr_->rows()),
        cols_(static_cast<std::size_t>(csr_->pixel_count)),
        dim_(csr_->local_count),
        light_host_(cols_),
        offsets_host_(rows_ + 1, 0),
        counts_host_(csr_->nnz()) {
    if (rows_ > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(
          fmt::format("{}: {} rows exceed the kernel's u32 row index", kName, rows_));
    offsets_host_[rows_] = static_cast<std::uint32_t>(csr_->nnz());
    columns_host_.resize(csr_->nnz() * csr_->column_bytes());
    KernelDefines defines;
    defines.set("PRT_WG_SIZE", kWorkGroup)
        .set("PRT_COLUMN_T", csr_->narrow_columns() ? "ushort" : "uint");
    const cl::Program program = build_program(ctx, "csr_zstd", defines);
    kernel_ = make_kernel(program, "csr_zstd_rows");
    vertices_kernel_ = make_kernel(program, "csr_zstd_vertices");
    offsets_ = make_buffer(ctx, offsets_host_.size() * 4, CL_MEM_READ_ONLY, "csr_zstd row offsets");
    columns_ = make_buffer(ctx, columns_host_.size(), CL_MEM_READ_ONLY, "csr_zstd column ids");
    counts_ = make_buffer(ctx, counts_host_.size(), CL_MEM_READ_ONLY, "csr_zstd counts");
    light_ = make_buffer(ctx, cols_ * sizeof(cl_float4), CL_MEM_READ_ONLY, "csr_zstd light");
    out_ = make_buffer(ctx, rows_ * sizeof(Rgb), CL_MEM_WRITE_ONLY, "csr_zstd local radiance");
    bytes_ = buffer_bytes({&offsets_, &columns_, &counts_, &light_, &out_});
    set_args(kernel_, static_cast<cl_uint>(rows_), static_cast<float>(csr_->scale()), offsets_,
             columns_, counts_, light_, out_);
  }

  bool supports_vertex_subset() const override { return true; }

  void set_vertex_subset(std::span<const std::uint32_t> vertices) override {
    check_vertex_subset(vertices, csr_->vertices, kName);
    tasks_ = frame_tasks(*csr_, vertices);
    subset_.assign(ctx_, vertices);
  }

  double relight_subset_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    const auto start = std::chrono::steady_clock::now();
    const std::size_t subset_rows = subset_.size() * static_cast<std::size_t>(dim_);
    if (subset_rows == 0) return 0.0;  // OpenCL forbids an empty launch
    decompress_subset_to_host();
    upload_subset_frames();
    upload_light(ctx_, light_, light.values, light_host_, "csr_zstd light");
    set_args(vertices_kernel_, static_cast<cl_uint>(subset_rows), static_cast<cl_uint>(dim_),
             subset_.buffer(), static_cast<float>(csr_->scale()), offsets_, columns_, counts_,
             light_, out_);
    cl::Event event = launch(ctx_, "csr_zstd.vertices", vertices_kernel_,
                             LaunchRange::linear(subset_rows, kWorkGroup));
    event.wait();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
  }

  double relight_on_device(const LightCoeffs& light) override {
    check_pixel_light(light, cols_, kName);
    const auto start = std::chrono::steady_clock::now();
    decompress_to_host();
    write_buffer(ctx_, offsets_, offsets_host_.data(), offsets_host_.size() * 4,
                 "csr_zstd row offsets");
    if (!columns_host_.empty()) {
      write_buffer(ctx_, columns_, columns_host_.data(), columns_host_.size(),
                   "csr_zstd column ids");
      write_buffer(ctx_, counts_, counts_host_.data(), counts_host_.size(), "csr_zstd counts");
    }
    upload_light(ctx_, light_, light.values, light_host_, "csr_zstd light");
    if (rows_ > 0) {  // OpenCL forbids an empty launch
      cl::Event event =
          launch(ctx_, "csr_zstd.rows", kernel_, LaunchRange::linear(rows_, kWorkGroup));
      event.wait();
    }
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
  }

  double relight(const LightCoeffs& light, LocalRadiance& out) override {
    const double ms = relight_on_device(light);
    out.ensure_shape(RadianceBasis::kPixel, csr_->local_count, csr_->vertices);
    download(ctx_, out_, std::span<Rgb>(out.values), "csr_zstd local radiance");
    return ms;
  }

  std::uint64_t device_bytes() const override { return bytes_; }
  const cl::Buffer& output_buffer() const override { return out_; }

 private:
  // Each frame writes its own rows' offsets (not the shared end, set once) and its own entries.
  void decompress_to_host() {
    const FramedCsr& csr = *csr_;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, csr.frame_count(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t f = r.begin(); f != r.end(); ++f)
                          copy_frame(decoder_.decode(csr, f));
                      });
  }

  // Frame f's rows' offsets and entries into the host arrays (not the offset after its last row,
  // which is the next frame's first and is written by the caller).
  void copy_frame(const FrameView& v) {
    const std::size_t column_bytes = csr_->column_bytes();
    const std::size_t entries = v.entry_end - v.entry_begin;
    std::memcpy(offsets_host_.data() + v.row_begin, v.offsets, 4 * (v.row_end - v.row_begin));
    // A frame without entries may have null column and count pointers (memcpy must not see them).
    if (entries == 0) return;
    const void* columns = v.columns16 != nullptr ? static_cast<const void*>(v.columns16)
                                                 : static_cast<const void*>(v.columns32);
    std::memcpy(columns_host_.data() + column_bytes * v.entry_begin, columns,
                column_bytes * entries);
    std::memcpy(counts_host_.data() + v.entry_begin, v.counts, entries);
  }

  // The frames of the subset only; the offset after each one's last row is set afterwards, so
  // that no two frames write the same element.
  void decompress_subset_to_host() {
    const FramedCsr& csr = *csr_;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks_.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t t = r.begin(); t != r.end(); ++t)
                          copy_frame(decoder_.decode(csr, tasks_[t].frame));
                      });
    for (const FrameTask& task : tasks_)
      offsets_host_[csr.frame_row_end(task.frame)] = csr.frame_entries[task.frame + 1];
  }

  // One write per array, from the subset's first frame to its last: the frames between that it
  // does not need go along stale (the kernel reads none of their rows), which costs less than a
  // blocking write per run of consecutive frames.
  void upload_subset_frames() {
    const FramedCsr& csr = *csr_;
    if (tasks_.empty()) return;
    const std::size_t column_bytes = csr.column_bytes();
    const std::size_t first = tasks_.front().frame, last = tasks_.back().frame;
    const std::size_t r0 = csr.frame_row_begin(first), r1 = csr.frame_row_end(last);
    write_buffer(ctx_, offsets_, offsets_host_.data() + r0, 4 * (r1 - r0 + 1),
                 "csr_zstd row offsets", 4 * r0);
    const std::size_t e0 = csr.frame_entries[first], e1 = csr.frame_entries[last + 1];
    if (e1 > e0) {
      write_buffer(ctx_, columns_, columns_host_.data() + column_bytes * e0,
                   column_bytes * (e1 - e0), "csr_zstd column ids", column_bytes * e0);
      write_buffer(ctx_, counts_, counts_host_.data() + e0, e1 - e0, "csr_zstd counts", e0);
    }
  }

  ClContext& ctx_;
  std::shared_ptr<const FramedCsr> csr_;
  FrameDecoder decoder_;
  std::size_t rows_, cols_;
  int dim_;
  std::vector<cl_float4> light_host_;
  std::vector<std::uint32_t> offsets_host_;
  std::vector<std::uint8_t> columns_host_;  // u16 or u32 ids as bytes, the layout of the buffer
  std::vector<std::uint8_t> counts_host_;
  cl::Kernel kernel_;
  cl::Buffer offsets_, columns_, counts_, light_, out_;
  std::uint64_t bytes_ = 0;
  // The vertex subset: its frames, and the kernel over its rows.
  std::vector<FrameTask> tasks_;
  cl::Kernel vertices_kernel_;
  DeviceIdList subset_{"csr_zstd vertex subset"};
};

}  // namespace

std::unique_ptr<DeviceRelighter> upload_frames(ClContext& context,
                                               std::shared_ptr<const FramedCsr> csr) {
  return std::make_unique<CsrZstdDevice>(context, std::move(csr));
}

}  // namespace prt::csr_zstd
