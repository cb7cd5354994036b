// traceGBuffer: the camera G-buffer by ray casting (src/rt/ray_scene.h), one primary ray
// through each pixel centre. It is the independent oracle the rasterizer's G-buffer is tested
// against: the same Camera::generateRay pixels, Embree's watertight hits instead of edge functions.
// Positions are interpolated from the triangle's vertices (float precision, world units); view depth
// is the ray parameter, which equals the view depth because the ray's camera-space z is -1.
#include <optional>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "penumbra/error.h"
#include "rt/ray_scene.h"

namespace penumbra {

GBuffer traceGBuffer(const Scene& scene, const RayScene& rays, int width, int height) {
  checkImageSize(width, height, "traceGBuffer");
  scene.camera.validate();
  GBuffer g(width, height);
  std::unordered_map<int32_t, const Mesh*> meshById;  // ids are unique within a scene
  for (const Object& object : scene.objects) {
    const Mesh& mesh = object.mesh;
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
      fail("{}: object '{}' has {} vertex normals for {} vertices (expected one per vertex, or none for flat shading)",
           scene.source, object.name, mesh.normals.size(), mesh.positions.size());
    meshById.emplace(object.id, &mesh);
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    for (int y = range.begin(); y < range.end(); ++y) {
      for (int x = 0; x < width; ++x) {
        const Ray ray =
            scene.camera.generateRay(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, width, height);
        const std::optional<RayHit> hit = rays.intersect(ray);
        if (!hit) continue;
        const auto found = meshById.find(hit->objectId);
        if (found == meshById.end())
          fail("traceGBuffer: the ray scene was not built from this scene (object id {} is not in it)", hit->objectId);
        const Mesh& mesh = *found->second;
        const glm::uvec3& tri = mesh.triangles[static_cast<size_t>(hit->triangleId)];
        const float b1 = hit->barycentrics.x, b2 = hit->barycentrics.y, b0 = 1.0f - b1 - b2;
        // Interpolating the vertices puts the point on the triangle to float precision; origin + t*dir
        // would carry the error of t times the ray's length.
        const Vec3 wsP = b0 * mesh.positions[tri.x] + b1 * mesh.positions[tri.y] + b2 * mesh.positions[tri.z];
        Vec3 ng = hit->wsGeometricNormal;
        Vec3 ns = ng;
        if (!mesh.normals.empty()) {
          const Vec3 n = b0 * mesh.normals[tri.x] + b1 * mesh.normals[tri.y] + b2 * mesh.normals[tri.z];
          const float len = glm::length(n);
          if (len > 0.0f && std::isfinite(len)) ns = n / len;
        }
        // Seen from behind: both normals turn to the visible side. The shading normal follows the
        // geometric one (rather than being flipped on its own sign) so that at a smooth silhouette,
        // where the interpolated normal may lean slightly away, it still describes the visible side.
        if (glm::dot(ng, ray.direction) > 0.0f) {
          ng = -ng;
          ns = -ns;
        }
        g.wsPosition(x, y) = wsP;
        g.wsNormal(x, y) = ns;
        g.wsGeometricNormal(x, y) = ng;
        g.objectId(x, y) = hit->objectId;
        g.triangleId(x, y) = hit->triangleId;
        g.csDepth(x, y) = hit->t;  // generateRay's direction has camera-space z = -1: t is the view depth
      }
    }
  });
  return g;
}

}  // namespace penumbra
