// A technique inside an "engine": the engine has its own triangles and its own G-buffer (here traced
// on the CPU, in an engine it comes from the GPU), hands both to penumbra as plain arrays
// (penumbra/engine.h) and gets V back. It runs pcss and the reference on the engine's buffers and
// prints pcss's RMSE8; then, as a check of the hand-over, the same pcss on penumbra's own G-buffer of
// the same triangles, and how many pixels' V differ between the two.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include "penumbra/engine.h"
#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/techniques/shadow_map.h"

namespace {

// The engine's data: a ground square (id 0) and a plate floating over it (id 1), as flat arrays.
struct EngineObject {
  int32_t id;
  std::vector<float> positions;
  std::vector<uint32_t> indices;
};

EngineObject quad(int32_t id, float y, float cx, float cz, float half) {
  return {id,
          {cx - half, y, cz - half, cx + half, y, cz - half, cx + half, y, cz + half, cx - half, y, cz + half},
          {0, 2, 1, 0, 3, 2}};
}

// The engine's own renderer: one primary ray per pixel against every triangle (Moller-Trumbore).
struct EngineFrame {
  int width, height;
  std::vector<float> position, normal;
  std::vector<int32_t> id;
};

EngineFrame renderEngineFrame(const std::vector<EngineObject>& objects, const penumbra::Camera& camera, int width,
                              int height) {
  EngineFrame f{width, height, std::vector<float>(3u * width * height), std::vector<float>(3u * width * height),
                std::vector<int32_t>(static_cast<size_t>(width) * height, penumbra::kNoObject)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const penumbra::Ray ray = camera.generateRay(x + 0.5f, y + 0.5f, width, height);
      float nearest = std::numeric_limits<float>::infinity();
      const size_t i = static_cast<size_t>(y) * width + x;
      for (const EngineObject& o : objects)
        for (size_t t = 0; t < o.indices.size(); t += 3) {
          auto vertex = [&](uint32_t k) {
            return penumbra::Vec3(o.positions[3 * k], o.positions[3 * k + 1], o.positions[3 * k + 2]);
          };
          const penumbra::Vec3 a = vertex(o.indices[t]), b = vertex(o.indices[t + 1]), c = vertex(o.indices[t + 2]);
          const penumbra::Vec3 e1 = b - a, e2 = c - a, p = glm::cross(ray.direction, e2);
          const float det = glm::dot(e1, p);
          if (std::abs(det) < 1e-12f) continue;
          const penumbra::Vec3 s = ray.origin - a, q = glm::cross(s, e1);
          const float u = glm::dot(s, p) / det, v = glm::dot(ray.direction, q) / det, d = glm::dot(e2, q) / det;
          if (u < 0.0f || v < 0.0f || u + v > 1.0f || !(d > 0.0f) || d >= nearest) continue;
          nearest = d;
          const penumbra::Vec3 hit = ray.origin + d * ray.direction, n = glm::normalize(glm::cross(e1, e2));
          for (int k = 0; k < 3; ++k) {
            f.position[3 * i + k] = hit[k];
            f.normal[3 * i + k] = n[k];
          }
          f.id[i] = o.id;
        }
    }
  return f;
}

}  // namespace

int main() {
  try {
    const std::vector<EngineObject> objects = {quad(0, 0.0f, 0.0f, 0.0f, 4.0f), quad(1, 1.0f, 0.3f, -0.2f, 0.8f)};
    penumbra::Camera camera;
    camera.position = penumbra::Vec3(0.0f, 5.0f, 6.0f);
    camera.lookAt = penumbra::Vec3(0.0f, 0.0f, 0.0f);
    const penumbra::Light light =
        penumbra::Light::disk(penumbra::Vec3(-0.5f, 4.0f, 0.5f), penumbra::Vec3(0, -1, 0), 0.6f);
    const int width = 320, height = 240;  // any size

    // What the engine hands over: spans over its arrays.
    std::vector<penumbra::EngineMesh> meshes;
    for (const EngineObject& o : objects) meshes.push_back({o.id, o.positions, o.indices});
    const EngineFrame frame = renderEngineFrame(objects, camera, width, height);
    penumbra::EngineGBuffer buffers;
    buffers.width = width;
    buffers.height = height;
    buffers.wsPosition = frame.position;
    buffers.wsNormal = frame.normal;
    buffers.objectId = frame.id;

    const penumbra::Scene scene = penumbra::makeScene(meshes, camera, light);
    const penumbra::GBuffer gbuffer = penumbra::makeGBuffer(buffers, camera, meshes);
    const auto pcss = penumbra::makeTechnique(penumbra::PcssOptions{});
    penumbra::Image<float> v, truth;
    pcss->prepare(scene, scene.lights[0]);
    pcss->visibility(gbuffer, v);
    penumbra::ReferenceOptions referenceOptions;
    referenceOptions.samplesPerPixel = 64;
    penumbra::ReferenceTechnique reference(referenceOptions);
    reference.prepare(scene, scene.lights[0]);
    reference.visibility(gbuffer, truth);
    const penumbra::ErrorStats error = penumbra::compareVisibility(v, truth, penumbra::errorMask(gbuffer, light));
    std::printf("engine buffers %dx%d: pcss RMSE8 %.2f against the reference at 64 spp\n", width, height, error.rmse8);

    // The same triangles through penumbra's own rasterizer: V should agree but at the edges of things.
    penumbra::Image<float> own;
    pcss->visibility(penumbra::renderGBuffer(scene, width, height), own);
    int differ = 0;
    for (size_t i = 0; i < v.size(); ++i) differ += std::abs(v[i] - own[i]) > 0.1f;
    std::printf("penumbra's own G-buffer: %.2f%% of pixels differ in V by more than 0.1\n",
                100.0 * differ / static_cast<double>(v.size()));
    return 0;
  } catch (const penumbra::Error& e) {
    std::fprintf(stderr, "engine: %s\n", e.what());
    return 1;
  }
}
