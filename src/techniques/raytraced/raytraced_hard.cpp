// `raytraced-hard`: one shadow ray per pixel to the light's centre sample — the exact hard shadow of
// a point light there (the "shadow volumes" row of Lawlor 2006, Fig. 10). V is 0 or 1; it is the
// baseline that shows how much of a soft shadow a single-sample technique must invent.
// Rays start off the surface and stop short of the centre exactly as the reference's do
// (src/rt/shadow_ray.h), so the two agree wherever the reference is 0 or 1.
#include <algorithm>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "rt/ray_scene.h"
#include "rt/shadow_packet.h"

namespace penumbra {
namespace {

class RaytracedHardTechnique final : public ShadowTechnique {
 public:
  std::string_view name() const override { return "raytraced-hard"; }

 private:
  void prepareImpl(const Scene& scene, const Light& light) override {
    // Every light shape has a centre sample, so every shape is supported.
    rays_ = nullptr;
    rays_ = &raysCache_.get(scene);  // built when the geometry changed, else kept
    light_ = light;
    epsilon_ = shadowRayEpsilon(raysCache_.bounds());
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (!rays_ || !light_)
      fail("raytraced-hard: visibility() called before prepare(); call prepare(scene, light) first");
    const int width = gbuffer.width(), height = gbuffer.height();
    resetInParallel(v, width, height, 1.0f);
    const Light& light = *light_;
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
      rt::ShadowLanes lanes;
      RayPacket16 packet;
      alignas(64) float facing[16];
      int xs[16];
      for (int y = range.begin(); y < range.end(); ++y) {
        // Neighbouring pixels of a row aim at the same point: a coherent packet, whose rays are made
        // sixteen at a time (rt::buildCenterRays: rt::shadowRay's, to the bit).
        int count = 0;
        auto flush = [&] {
          rt::buildCenterRays(light, lanes, count, epsilon_, packet, facing);
          rays_->occluded16(packet, count);
          float* row = v.row(y);
          for (int i = 0; i < count; ++i) row[xs[i]] = packet.blocked(i) ? 0.0f : 1.0f;
          count = 0;
        };
        const int32_t* ids = gbuffer.objectId.row(y);
        const Vec3* positions = gbuffer.wsPosition.row(y);
        const Vec3* normals = gbuffer.wsGeometricNormal.row(y);
        for (int x = 0; x < width; ++x) {
          if (ids[x] == kNoObject) continue;
          lanes.setSurface(count, positions[x], normals[x]);
          xs[count++] = x;
          if (count == 16) flush();
        }
        if (count > 0) flush();
      }
    });
  }

  RaySceneCache raysCache_;
  const RayScene* rays_ = nullptr;
  std::optional<Light> light_;
  float epsilon_ = 0.0f;
};

}  // namespace

TechniqueInfo raytracedHardTechniqueInfo() {
  TechniqueInfo info;
  info.name = "raytraced-hard";
  info.summary = "one shadow ray per pixel to the light's centre: the exact hard shadow";
  info.source = "baseline (the \"shadow volumes\" row of Lawlor 2006)";
  info.tracesRays = true;
  info.create = [](const Params&) -> std::unique_ptr<ShadowTechnique> {
    return std::make_unique<RaytracedHardTechnique>();
  };
  return info;
}

}  // namespace penumbra
