#include "prtlab/render/btf_table_material.h"

#include <algorithm>
#include <map>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt {
namespace {

// The floats of `b` on the device: a view-independent BTF keeps only view 0 of each texel (every
// other view holds the same values, and the kernel reads none of them).
std::uint64_t device_values(const Btf& b) {
  return b.view_independent() ? static_cast<std::uint64_t>(b.texel_count()) * b.light_count() * 3
                              : b.value_count();
}

void write_btf_values(ClContext& context, const cl::Buffer& data, const Btf& b,
                      std::uint64_t offset, const std::string& what) {
  if (!b.view_independent()) {
    write_buffer(context, data, b.data().data(), b.bytes(), what, offset * sizeof(float));
    return;
  }
  const std::size_t vector = static_cast<std::size_t>(b.light_count()) * 3;
  std::vector<float> one_view(static_cast<std::size_t>(device_values(b)));
  for (int t = 0; t < b.texel_count(); ++t) {
    const auto v = b.light_vector(t, 0);
    std::copy(v.begin(), v.end(), one_view.begin() + static_cast<std::ptrdiff_t>(t * vector));
  }
  write_buffer(context, data, one_view.data(), one_view.size() * sizeof(float), what,
               offset * sizeof(float));
}

class BtfTableDeviceMaterial final : public DeviceMaterial {
 public:
  BtfTableDeviceMaterial(ClContext& context, std::span<const Btf* const> parts, std::string label)
      : label_(std::move(label)) {
    // Distinct BTFs once each, in part order, into one buffer.
    std::map<const Btf*, std::uint64_t> offset_of;
    std::vector<const Btf*> order;
    std::uint64_t total = 0;
    for (const Btf* b : parts) {
      if (offset_of.emplace(b, total).second) {
        order.push_back(b);
        total += device_values(*b);
      }
    }
    data_ =
        make_buffer(context, total * sizeof(float), CL_MEM_READ_ONLY, label_ + " material tables");
    for (const Btf* b : order)
      write_btf_values(context, data_, *b, offset_of.at(b), label_ + " material tables");
    std::vector<cl_ulong> offsets;
    std::vector<cl_int4> info;
    for (const Btf* part : parts) {
      const Btf& b = *part;
      offsets.push_back(offset_of.at(&b));
      info.push_back(cl_int4{{b.resolution(), b.view_side(), b.view_independent() ? 1 : 0, 0}});
      views_read_.push_back(b.view_independent() ? 1 : 4);
      view_sides_.push_back(b.view_independent() ? 0 : b.view_side());
    }
    m_ = parts.front()->light_count();
    part_offset_ =
        upload(context, std::span<const cl_ulong>(offsets), label_ + " material offsets");
    part_info_ = upload(context, std::span<const cl_int4>(info), label_ + " material part table");
    bytes_ =
        total * sizeof(float) + offsets.size() * sizeof(cl_ulong) + info.size() * sizeof(cl_int4);
  }

  std::string label() const override { return "btf_table_material.cl (" + label_ + ")"; }
  std::string source() const override { return std::string(kernel_source("btf_table_material")); }
  void set_args(cl::Kernel& kernel, unsigned first) const override {
    set_args_from(kernel, first, data_, part_offset_, part_info_);
  }
  std::uint64_t device_bytes() const override { return bytes_; }
  std::vector<int> view_sides() const override { return view_sides_; }
  bool view_cache_useful(std::size_t part, TexelFilter filter) const override {
    return views_read_.at(part) > 1 || filter == TexelFilter::kBilinear;
  }
  std::uint64_t bytes_per_hit(std::size_t part, TexelFilter filter) const override {
    const std::uint64_t texels = filter == TexelFilter::kBilinear ? 4 : 1;
    return texels * static_cast<std::uint64_t>(views_read_.at(part)) *
           static_cast<std::uint64_t>(m_) * 3 * sizeof(float);
  }

 private:
  cl::Buffer data_, part_offset_, part_info_;
  std::vector<int> views_read_;  // view vectors a hit pixel of each part reads per texel
  std::vector<int> view_sides_;  // per part, its view grid's side (0: view-independent)
  std::string label_;
  int m_ = 0;
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceMaterial> upload_btf_tables(ClContext& context,
                                                  std::span<const Btf* const> parts,
                                                  std::string label) {
  PRT_CHECK(!parts.empty(), "material {}: no parts to upload", label);
  const int dim = parts.front()->light_count();
  for (const Btf* p : parts)
    PRT_CHECK(p != nullptr && p->light_count() == dim,
              "material {}: the parts' tables differ in their light dimension", label);
  return std::make_unique<BtfTableDeviceMaterial>(context, parts, std::move(label));
}

}  // namespace prt
