// The fuzzed entry point of technique parameters: (technique, light shape, "name=value" lines) on a
// small scene, shared by the libFuzzer target (tests/fuzz/technique_params_fuzz.cpp, `make fuzz`) and
// by the test that replays its committed corpus in the normal suite
// (tests/techniques/technique_params_corpus_test.cpp).
//
// The contract under test: any parameter names and values, as a user types them after --param, end
// either in one penumbra::Error (an unknown name, a value out of range or of the wrong type, a light
// shape the technique does not take) or in V finite and in [0, 1] for every pixel. Anything else
// escapes (libFuzzer reports it as a crash, the replay test as a failure); a crash, a sanitizer
// finding or a hang is found by the fuzzer itself. Runs that the CLI's up-front check would refuse
// as too large (ResourceEstimate) are skipped, as a user's would be: the fuzzer looks for crashes,
// not for the machine's memory.
//
// Input layout: byte 0 picks the technique (modulo the registry's size), byte 1 the light shape
// (sphere, disk, rect, concave polygon, segment, directional), the rest is text, one name=value a line.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene.h"

namespace penumbra::fuzz {

// The small scene the parameter fuzzer and the parameter range sweep (tests/techniques/
// param_range_test.cpp) run on: its lights stand at kSmallSceneLightCenter, one of each shape.
inline const Vec3 kSmallSceneLightCenter(0.2f, 4.0f, 0.1f);
inline constexpr int kSmallSceneLightShapes = 6;

// Light `pick` (modulo kSmallSceneLightShapes): a sphere, a disk, a rect, a concave L polygon, a
// segment and a directional light.
inline Light smallSceneLight(uint8_t pick) {
  const Vec3 c = kSmallSceneLightCenter;
  switch (pick % kSmallSceneLightShapes) {
    case 0:
      return Light::sphere(c, 0.4f);
    case 1:
      return Light::disk(c, Vec3(0.0f, -1.0f, 0.0f), 0.4f);
    case 2:
      return Light::rect(c, Vec3(0.4f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.3f));
    case 3:
      return Light::polygon({c + Vec3(-0.5f, 0.0f, -0.5f), c + Vec3(0.5f, 0.0f, -0.5f), c + Vec3(0.5f, 0.0f, 0.0f), c,
                             c + Vec3(0.0f, 0.0f, 0.5f), c + Vec3(-0.5f, 0.0f, 0.5f)});
    case 4:
      return Light::segment(c - Vec3(0.6f, 0.0f, 0.0f), c + Vec3(0.6f, 0.0f, 0.0f));
    default:
      return Light::directional(Vec3(0.3f, 1.0f, 0.2f), radians(3.0f));
  }
}

// A ground, a box resting on it, a sphere floating above it and a thin open sheet tilted over it (a
// solid, a curved occluder and an open one, with contact), lit by `light`: small enough for
// thousands of runs a second at 8 x 8 pixels.
inline Scene smallScene(const Light& light) {
  Scene scene;
  const auto add = [&](int32_t id, Mesh mesh, const Mat4& transform) {
    transformMesh(mesh, transform);
    Object object;
    object.id = id;
    object.mesh = std::move(mesh);
    scene.objects.push_back(std::move(object));
  };
  add(0, makePlane(4.0f, 4.0f), Mat4(1.0f));
  add(1, makeBox(Vec3(0.6f)), glm::translate(Mat4(1.0f), Vec3(-0.6f, 0.3f, 0.0f)));
  add(2, makeSphere(0.3f, 12, 6), glm::translate(Mat4(1.0f), Vec3(0.6f, 1.0f, 0.2f)));
  add(3, makePlane(0.8f, 0.5f),
      glm::translate(Mat4(1.0f), Vec3(0.0f, 1.6f, -0.5f)) *
          glm::rotate(Mat4(1.0f), radians(30.0f), Vec3(1.0f, 0.0f, 0.0f)));
  scene.lights.push_back(light);
  scene.camera.position = Vec3(0.0f, 4.0f, 4.0f);
  scene.camera.lookAt = Vec3(0.0f, 0.3f, 0.0f);
  return scene;
}

inline constexpr int kFuzzImageSize = 8;

inline void techniqueParams(const uint8_t* data, size_t size) {
  if (size < 2) return;
  const std::vector<TechniqueInfo>& registry = techniqueRegistry();
  const TechniqueInfo& info = registry[data[0] % registry.size()];
  const Light light = smallSceneLight(data[1]);
  ParamSet given;
  std::istringstream lines(std::string(reinterpret_cast<const char*>(data + 2), size - 2));
  std::string line;
  Params params;
  try {
    while (std::getline(lines, line))
      if (!line.empty()) given.setFromKeyValue(line, "fuzz");
    params = resolveParams(info.name, info.params, given);
  } catch (const Error&) {
    return;
  }
  const ResourceEstimate cost = info.estimate(params, kFuzzImageSize, kFuzzImageSize);
  if (cost.bytes > 256.0 * 1024.0 * 1024.0 || cost.rays > 1.0e7 || cost.texels > 1.0e8) return;
  const Scene scene = smallScene(light);
  const GBuffer gbuffer = renderGBuffer(scene, kFuzzImageSize, kFuzzImageSize);
  Image<float> v;
  try {
    auto technique = info.create(params);
    technique->prepare(scene, light);
    technique->visibility(gbuffer, v);
  } catch (const Error&) {
    return;
  }
  if (v.width() != kFuzzImageSize || v.height() != kFuzzImageSize)
    throw std::logic_error(info.name + ": V does not have the G-buffer's size");
  for (float x : v)
    if (!(std::isfinite(x) && x >= 0.0f && x <= 1.0f))
      throw std::logic_error(info.name + ": V outside [0, 1] or not finite");
}

}  // namespace penumbra::fuzz
