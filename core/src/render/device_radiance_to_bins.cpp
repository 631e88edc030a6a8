#include "prtlab/render/device_radiance_to_bins.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt {
namespace {
constexpr std::size_t kWorkGroup = 64;

int order_of(int count) {
  for (int order = 1; order <= kMaxShOrder; ++order)
    if (sh_count(order) == count) return order;
  throw ParameterError(fmt::format("{} SH coefficients per vertex is no order^2", count));
}
}  // namespace

struct DeviceRadianceToBins::Impl {
  ClContext& ctx;
  std::size_t vertices;
  std::size_t values;  // vertices * M
  cl::Kernel kernel;
  cl::Buffer b, out;
};

DeviceRadianceToBins::DeviceRadianceToBins(ClContext& context, const HemisphereGrid& grid,
                                           int sh_count_per_vertex, std::size_t vertices) {
  const std::vector<double> b = sh_cell_integrals(grid, order_of(sh_count_per_vertex));
  const std::vector<float> bf(b.begin(), b.end());
  const std::size_t m = static_cast<std::size_t>(grid.cell_count());
  // A braced temporary moved in: clang before 16 has no parenthesised aggregate initialisation.
  impl_ = std::make_unique<Impl>(Impl{context, vertices, vertices * m});
  KernelDefines defines;
  defines.set("PRT_WG_SIZE", kWorkGroup)
      .set("PRT_SH_COUNT", sh_count_per_vertex)
      .set("PRT_LOCAL_COUNT", grid.cell_count());
  impl_->kernel =
      make_kernel(build_program(context, "radiance_to_bins", defines), "radiance_sh_to_bins");
  impl_->b = upload(context, std::span<const float>(bf), "SH cell integrals");
  impl_->out = make_buffer(context, impl_->values * sizeof(Rgb), CL_MEM_READ_WRITE,
                           "local radiance at the bins");
}

DeviceRadianceToBins::~DeviceRadianceToBins() = default;
DeviceRadianceToBins::DeviceRadianceToBins(DeviceRadianceToBins&&) noexcept = default;
DeviceRadianceToBins& DeviceRadianceToBins::operator=(DeviceRadianceToBins&&) noexcept = default;

double DeviceRadianceToBins::run(const cl::Buffer& sh) {
  Impl& s = *impl_;
  if (s.values == 0) return 0.0;
  set_args(s.kernel, static_cast<cl_uint>(s.vertices), s.b, sh, s.out);
  cl::Event e =
      launch(s.ctx, "radiance_sh_to_bins", s.kernel, LaunchRange::linear(s.values, kWorkGroup));
  return event_milliseconds(e, s.ctx.info().device_name, "timing of kernel radiance_sh_to_bins");
}

const cl::Buffer& DeviceRadianceToBins::output_buffer() const {
  return impl_->out;
}

}  // namespace prt
