#include "geometry/embree_triangle_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <mutex>
#include <string>

#include "prtlab/base/error.h"

namespace prt {
namespace {

// Embree reports errors through a callback; keep the first one so the exception says why.
struct DeviceError {
  std::mutex mutex;
  std::string first;
};

void on_embree_error(void* user, RTCError code, const char* message) {
  auto* err = static_cast<DeviceError*>(user);
  std::lock_guard lock(err->mutex);
  if (err->first.empty())
    err->first = fmt::format("Embree error {}: {}", static_cast<int>(code), message ? message : "");
}

}  // namespace

struct EmbreeTriangleScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  DeviceError error;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void check(const char* what) {
    std::lock_guard lock(error.mutex);
    if (!error.first.empty()) throw Error(fmt::format("{} failed: {}", what, error.first));
  }
};

EmbreeTriangleScene::EmbreeTriangleScene(std::span<const Vec3> positions,
                                         std::span<const std::uint32_t> indices)
    : impl_(std::make_unique<Impl>()) {
  const std::size_t triangles = indices.size() / 3;
  if (triangles == 0) throw ParameterError("Embree scene: the mesh has no triangles");
  Impl& im = *impl_;
  im.device = rtcNewDevice(nullptr);
  if (!im.device)
    throw Error(fmt::format("Embree: rtcNewDevice failed (error {})",
                            static_cast<int>(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(im.device, on_embree_error, &im.error);
  RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), positions.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles));
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    im.check("Embree geometry buffer allocation");
    throw Error("Embree: geometry buffer allocation failed");
  }
  for (std::size_t v = 0; v < positions.size(); ++v) {
    vb[3 * v + 0] = positions[v].x;
    vb[3 * v + 1] = positions[v].y;
    vb[3 * v + 2] = positions[v].z;
  }
  std::copy(indices.begin(), indices.begin() + 3 * triangles, ib);
  rtcCommitGeometry(geom);
  im.scene = rtcNewScene(im.device);
  rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_HIGH);
  rtcAttachGeometry(im.scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(im.scene);
  im.check("Embree scene build");
}

EmbreeTriangleScene::~EmbreeTriangleScene() = default;
EmbreeTriangleScene::EmbreeTriangleScene(EmbreeTriangleScene&&) noexcept = default;
EmbreeTriangleScene& EmbreeTriangleScene::operator=(EmbreeTriangleScene&&) noexcept = default;

RTCScene EmbreeTriangleScene::scene() const {
  return impl_->scene;
}

}  // namespace prt
