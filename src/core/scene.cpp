#include "penumbra/scene.h"

#include "core/scene_caches.h"
#include "penumbra/error.h"

namespace penumbra {

void checkImageSize(int width, int height, const std::string& where) {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
    fail("{}: image size {} x {} must be within 1..{} pixels per side", where, width, height, kMaxImageSide);
  const int64_t pixels = int64_t{width} * height;
  if (pixels > kMaxImagePixels)
    fail(
        "{}: image size {} x {} is {} pixels, over the limit of {} pixels (8192 x 8192: the G-buffer alone takes "
        "48 bytes per pixel); render a smaller image",
        where, width, height, pixels, kMaxImagePixels);
}

Bounds3 Mesh::bounds() const {
  Bounds3 b;
  for (const Vec3& p : positions) b.extend(p);
  return b;
}

Vec3 Mesh::faceNormal(size_t i) const {
  const glm::uvec3& t = triangles[i];
  const Vec3 n = glm::cross(positions[t.y] - positions[t.x], positions[t.z] - positions[t.x]);
  const float len = glm::length(n);
  return len > 0.0f ? n / len : Vec3(0.0f);
}

std::shared_ptr<SceneCaches> makeSceneCaches() { return std::make_shared<SceneCaches>(); }

void Scene::declareGeometry() {
  if (!caches) {
    geometryRevision = 0;
    return;
  }
  std::lock_guard lock(caches->mutex);
  geometryRevision = caches->nextRevision++;
}

Bounds3 Scene::bounds() const {
  Bounds3 b;
  for (const Object& o : objects) b.extend(o.mesh.bounds());
  return b;
}

size_t Scene::triangleCount() const {
  size_t n = 0;
  for (const Object& o : objects) n += o.mesh.triangleCount();
  return n;
}

const Object* Scene::findObject(int32_t id) const {
  for (const Object& o : objects)
    if (o.id == id) return &o;
  return nullptr;
}

}  // namespace penumbra
