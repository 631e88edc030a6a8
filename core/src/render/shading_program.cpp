#include "render/shading_program.h"

#include <fmt/format.h>

#include <array>
#include <string>

#include "prtlab/opencl/cl_kernel_sources.h"
#include "prtlab/opencl/cl_program.h"

namespace prt {

cl::Program build_shading_program(ClContext& context, const DeviceMaterial& material, int m,
                                  TexelFilter filter, ShadingProbe probe) {
  KernelDefines defines = material.defines();
  defines.set("PRT_WG_SIZE", kShadingWorkGroup)
      .set("PRT_M", m)
      .set("PRT_BILINEAR", filter == TexelFilter::kBilinear ? 1 : 0);
  // Indexed by ShadingProbe.
  static constexpr std::array<const char*, 5> kProbeDefine = {
      nullptr, "PRT_PROBE_NO_VECTOR_READS", "PRT_PROBE_NO_CACHE_WRITES", "PRT_PROBE_FIXED_VIEWS",
      "PRT_PROBE_LAUNCH_ONLY"};
  if (const char* probe_define = kProbeDefine.at(static_cast<std::size_t>(probe)))
    defines.set(probe_define);
  const std::string label = material.label();
  // #line markers keep the compiler's messages pointing at each file's own lines.
  std::string source(kernel_source("btf_lookup"));
  source += fmt::format("\n#line 1 \"{}\"\n", label);
  source += material.source();
  source += "\n#line 1 \"btf_shading.cl\"\n";
  source += kernel_source("btf_shading");
  return build_program_source(context, "btf_lookup.cl", source, defines);
}

}  // namespace prt
