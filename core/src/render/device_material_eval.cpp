#include "prtlab/render/device_material_eval.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_runtime.h"
#include "render/shading_program.h"

namespace prt {

std::vector<Rgb> evaluate_materials_on_device(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    std::span<const MaterialQuery> queries, TexelFilter filter,
    const std::map<std::string, std::string>& device_options) {
  const auto device = upload_materials(context, parts, device_options);
  const int m = parts.front()->light_basis().dim;
  std::vector<Rgb> out(queries.size() * static_cast<std::size_t>(m));
  if (queries.empty()) return out;  // OpenCL forbids an empty launch
  std::vector<cl_int2> ids;
  std::vector<cl_float4> geom, view;
  for (const MaterialQuery& q : queries) {
    if (q.part < 0 || static_cast<std::size_t>(q.part) >= parts.size())
      throw ParameterError(
          fmt::format("material evaluation: part {} of {} parts", q.part, parts.size()));
    ids.push_back(cl_int2{{0, q.part}});
    geom.push_back(cl_float4{{0.0f, 0.0f, q.uv.x, q.uv.y}});
    view.push_back(cl_float4{{q.view_local.x, q.view_local.y, q.view_local.z, 0.0f}});
  }
  const cl::Program program = build_shading_program(context, *device, m, filter);
  cl::Kernel kernel = make_kernel(program, "btf_view_cache");
  const cl::Buffer ids_buf = upload(context, std::span<const cl_int2>(ids), "material queries");
  const cl::Buffer geom_buf = upload(context, std::span<const cl_float4>(geom), "material queries");
  const cl::Buffer view_buf = upload(context, std::span<const cl_float4>(view), "material queries");
  const cl::Buffer result =
      make_buffer(context, out.size() * sizeof(Rgb), CL_MEM_WRITE_ONLY, "material vectors");
  set_args(kernel, static_cast<cl_uint>(queries.size()), ids_buf, geom_buf, view_buf, result);
  device->set_args(kernel, kViewCacheMaterialArg);
  cl::Event ev = launch(context, "btf_view_cache", kernel,
                        LaunchRange::linear(queries.size(), kShadingWorkGroup));
  ev.wait();
  download(context, result, std::span<Rgb>(out), "material vectors");
  return out;
}

}  // namespace prt
