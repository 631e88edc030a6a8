#include <fmt/format.h>

#include <map>
#include <vector>

#include "packed/packed.h"
#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt::packed {
namespace {

class PackedDeviceMaterial final : public DeviceMaterial {
 public:
  PackedDeviceMaterial(ClContext& context, std::span<const PackedMaterial* const> parts)
      : storage_(parts.front()->storage_kind()) {
    const std::size_t len = static_cast<std::size_t>(parts.front()->sampling().light_count()) * 3;
    // Distinct materials once each, in part order: codes, scales (u8) and texel slots.
    std::map<const PackedMaterial*, cl_int4> placed;
    std::vector<std::uint16_t> halves;
    std::vector<std::uint8_t> bytes;
    std::vector<float> scales;
    std::vector<std::int32_t> slots;
    std::vector<cl_ulong> vector_base;
    std::vector<cl_int4> info;
    std::uint64_t vectors = 0;
    for (const PackedMaterial* p : parts) {
      auto it = placed.find(p);
      if (it == placed.end()) {
        const MaterialSampling s = p->sampling();
        const cl_int4 i{{s.resolution, s.view_side, p->stored_views() == 1 ? 1 : 0,
                         static_cast<cl_int>(slots.size())}};
        it = placed.emplace(p, i).first;
        base_of_[p] = vectors;
        slots.insert(slots.end(), p->texel_slot().begin(), p->texel_slot().end());
        if (storage_ == Storage::kHalf) {
          halves.insert(halves.end(), p->halves().begin(), p->halves().end());
        } else {
          bytes.insert(bytes.end(), p->bytes().begin(), p->bytes().end());
          scales.insert(scales.end(), p->scales().begin(), p->scales().end());
        }
        vectors += static_cast<std::uint64_t>(s.texel_count()) * p->stored_views();
      }
      vector_base.push_back(base_of_.at(p));
      info.push_back(it->second);
      views_read_.push_back(p->stored_views() == 1 ? 1 : 4);
      view_sides_.push_back(p->stored_views() == 1 ? 0 : p->sampling().view_side);
    }
    if (vectors * len >= (std::uint64_t{1} << 32))
      throw ParameterError(
          fmt::format("material packed: {} values exceed the device's 32-bit "
                      "indexing",
                      vectors * len));
    const std::string what = "packed material codes";
    if (storage_ == Storage::kHalf) {
      codes_ = upload(context, std::span<const std::uint16_t>(halves), what);
      scales_ = make_buffer(context, sizeof(float), CL_MEM_READ_ONLY, "packed material scales");
    } else {
      codes_ = upload(context, std::span<const std::uint8_t>(bytes), what);
      scales_ = upload(context, std::span<const float>(scales), "packed material scales");
    }
    slots_ = upload(context, std::span<const std::int32_t>(slots), "packed texel slots");
    part_base_ = upload(context, std::span<const cl_ulong>(vector_base), "packed part offsets");
    part_info_ = upload(context, std::span<const cl_int4>(info), "packed part table");
    bytes_ = buffer_bytes({&codes_, &scales_, &slots_, &part_base_, &part_info_});
    value_bytes_ = storage_ == Storage::kHalf ? 2 : 1;
    m_ = parts.front()->sampling().light_count();
  }

  std::string label() const override { return "packed.cl"; }
  std::string source() const override { return std::string(kernel_source("packed")); }
  KernelDefines defines() const override {
    return {{"PACKED_U8", storage_ == Storage::kByte ? "1" : "0"}};
  }
  void set_args(cl::Kernel& kernel, unsigned first) const override {
    set_args_from(kernel, first, codes_, scales_, slots_, part_base_, part_info_);
  }
  std::uint64_t device_bytes() const override { return bytes_; }
  bool view_cache_useful(std::size_t, TexelFilter) const override { return true; }
  std::vector<int> view_sides() const override { return view_sides_; }
  std::uint64_t bytes_per_hit(std::size_t part, TexelFilter filter) const override {
    const std::uint64_t texels = filter == TexelFilter::kBilinear ? 4 : 1;
    const std::uint64_t per_vector = static_cast<std::uint64_t>(m_) * 3 * value_bytes_ +
                                     (storage_ == Storage::kByte ? sizeof(float) : 0);
    return texels * static_cast<std::uint64_t>(views_read_.at(part)) * per_vector;
  }

 private:
  Storage storage_;
  cl::Buffer codes_, scales_, slots_, part_base_, part_info_;
  std::map<const PackedMaterial*, std::uint64_t> base_of_;
  std::vector<int> views_read_;
  std::vector<int> view_sides_;  // per part, its view grid's side (0: one stored view)
  std::uint64_t bytes_ = 0, value_bytes_ = 1;
  int m_ = 0;
};

}  // namespace

std::unique_ptr<DeviceMaterial> upload_packed(ClContext& context,
                                              std::span<const PackedMaterial* const> parts) {
  PRT_CHECK(!parts.empty(), "material packed: no parts to upload");
  for (const PackedMaterial* p : parts) {
    if (p->storage_kind() != parts.front()->storage_kind())
      throw ParameterError(fmt::format(
          "material packed: the parts mix storage {} and {}; one shading program "
          "reads one kind",
          storage_name(parts.front()->storage_kind()), storage_name(p->storage_kind())));
    if (p->sampling().light_count() != parts.front()->sampling().light_count())
      throw ParameterError("material packed: the parts differ in their light dimension");
  }
  return std::make_unique<PackedDeviceMaterial>(context, parts);
}

}  // namespace prt::packed
