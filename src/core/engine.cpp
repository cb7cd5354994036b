// makeScene and makeGBuffer (penumbra/engine.h): the engine's arrays checked and copied into
// penumbra's scene and G-buffer.
#include "penumbra/engine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "penumbra/error.h"

namespace penumbra {

Scene makeScene(const std::vector<EngineMesh>& meshes, const Camera& camera, const Light& light) {
  camera.validate();
  Scene scene;
  scene.name = "engine";
  scene.source = "engine buffers";
  scene.camera = camera;
  scene.lights.push_back(light);
  std::set<int32_t> ids;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const EngineMesh& in = meshes[m];
    if (in.id < 0 || !ids.insert(in.id).second)
      fail("engine mesh {}: id {} is not valid: expected an id >= 0 that no other mesh has", m, in.id);
    if (in.positions.size() % 3 != 0 || in.indices.size() % 3 != 0)
      fail(
          "engine mesh {} (id {}): {} position floats and {} indices: expected three per vertex and three per "
          "triangle",
          m, in.id, in.positions.size(), in.indices.size());
    Object object;
    object.name = "mesh " + std::to_string(in.id);
    object.id = in.id;
    const size_t vertices = in.positions.size() / 3;
    object.mesh.positions.resize(vertices);
    for (size_t v = 0; v < vertices; ++v) {
      const Vec3 p(in.positions[3 * v], in.positions[3 * v + 1], in.positions[3 * v + 2]);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        fail("engine mesh {} (id {}): vertex {} is not finite: expected finite world coordinates", m, in.id, v);
      object.mesh.positions[v] = p;
    }
    object.mesh.triangles.resize(in.indices.size() / 3);
    for (size_t t = 0; t < object.mesh.triangles.size(); ++t) {
      const glm::uvec3 tri(in.indices[3 * t], in.indices[3 * t + 1], in.indices[3 * t + 2]);
      if (tri.x >= vertices || tri.y >= vertices || tri.z >= vertices)
        fail("engine mesh {} (id {}): triangle {} indexes vertex {}: expected indices below its {} vertices", m, in.id,
             t, std::max({tri.x, tri.y, tri.z}), vertices);
      object.mesh.triangles[t] = tri;
    }
    scene.objects.push_back(std::move(object));
  }
  return scene;
}

GBuffer makeGBuffer(const EngineGBuffer& b, const Camera& camera, const std::vector<EngineMesh>& meshes) {
  checkImageSize(b.width, b.height, "engine G-buffer");
  const size_t pixels = static_cast<size_t>(b.width) * b.height;
  auto checkLength = [&](const char* name, size_t length, size_t perPixel, bool optional) {
    if (optional && length == 0) return;
    if (length == 0)
      fail("engine G-buffer: {} is missing: expected world positions, shading normals and object ids", name);
    if (length != pixels * perPixel)
      fail("engine G-buffer: {} holds {} values: expected {} ({} x {} pixels, {} a pixel)", name, length,
           pixels * perPixel, b.width, b.height, perPixel);
  };
  checkLength("wsPosition", b.wsPosition.size(), 3, false);
  checkLength("wsNormal", b.wsNormal.size(), 3, false);
  checkLength("objectId", b.objectId.size(), 1, false);
  checkLength("csDepth", b.csDepth.size(), 1, true);
  checkLength("wsGeometricNormal", b.wsGeometricNormal.size(), 3, true);
  camera.validate();
  std::set<int32_t> ids;
  for (const EngineMesh& m : meshes) ids.insert(m.id);
  GBuffer g(b.width, b.height);
  const Mat4 cameraFromWs = camera.cameraFromWs();
  const Vec3 eye = camera.position;
  auto unitTowardsCamera = [&](const float* n, const Vec3& p, int x, int y, const char* buffer) {
    Vec3 v(n[0], n[1], n[2]);
    const float length = glm::length(v);
    if (!std::isfinite(length) || !(length > 0.0f))
      fail("engine G-buffer: {} at pixel ({}, {}) is ({}, {}, {}): expected a finite, non-zero normal", buffer, x, y,
           v.x, v.y, v.z);
    // A normal already unit to float rounding is kept to the bit: divided again, its last bits would
    // move, and an engine's copy of penumbra's own G-buffer would no longer give the same V.
    if (std::abs(length - 1.0f) > 8.0f * std::numeric_limits<float>::epsilon()) v /= length;
    return glm::dot(v, eye - p) < 0.0f ? -v : v;
  };
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x) {
      const size_t i = static_cast<size_t>(y) * b.width + x;
      const int32_t id = b.objectId[i];
      if (id == kNoObject) continue;  // the defaults of GBuffer: sees nothing
      if (!ids.count(id))
        fail(
            "engine G-buffer: objectId at pixel ({}, {}) is {}: expected kNoObject (-1) or the id of one of the {} "
            "meshes",
            x, y, id, meshes.size());
      const Vec3 p(b.wsPosition[3 * i], b.wsPosition[3 * i + 1], b.wsPosition[3 * i + 2]);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        fail(
            "engine G-buffer: wsPosition at pixel ({}, {}) is not finite: expected world coordinates where the "
            "pixel sees mesh {}",
            x, y, id);
      g.objectId(x, y) = id;
      g.wsPosition(x, y) = p;
      g.wsNormal(x, y) = unitTowardsCamera(b.wsNormal.data() + 3 * i, p, x, y, "wsNormal");
      g.wsGeometricNormal(x, y) = b.wsGeometricNormal.empty() ? g.wsNormal(x, y)
                                                              : unitTowardsCamera(b.wsGeometricNormal.data() + 3 * i, p,
                                                                                  x, y, "wsGeometricNormal");
      g.triangleId(x, y) = -1;  // not known from the engine's buffers; no technique needs it
      const float depth = b.csDepth.empty() ? -(cameraFromWs * Vec4(p, 1.0f)).z : b.csDepth[i];
      if (!std::isfinite(depth) || !(depth > 0.0f))
        fail(
            "engine G-buffer: {} at pixel ({}, {}) is {}: expected a finite view depth above 0 (in front of the "
            "camera)",
            b.csDepth.empty() ? "the view depth of wsPosition" : "csDepth", x, y, depth);
      g.csDepth(x, y) = depth;
    }
  return g;
}

}  // namespace penumbra
