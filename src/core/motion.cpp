// Motion: frames of a light or camera moving along a path (include/penumbra/motion.h).
#include "penumbra/motion.h"

#include <cmath>

#include "penumbra/error.h"
#include "penumbra/scene.h"

namespace penumbra {

void Motion::validate(const Scene& scene, const std::string& where) const {
  if (path.size() < 2)
    fail("{}: path has {} key point(s): expected at least 2 (a segment is two keys)", where, path.size());
  for (size_t i = 0; i < path.size(); ++i)
    if (!isFinite(path[i])) fail("{}: path key {} is not finite", where, i);
  double length = 0.0;
  for (size_t i = 1; i < path.size(); ++i) length += glm::length(DVec3(path[i]) - DVec3(path[i - 1]));
  if (!(length > 0.0)) fail("{}: path has zero length: its keys are all the same point", where);
  if (frames < 2 || frames > kMaxMotionFrames)
    fail("{}: frames = {}: expected an int in [2, {}]", where, frames, kMaxMotionFrames);
  if (target == MotionTarget::Light) {
    if (lightIndex < 0 || static_cast<size_t>(lightIndex) >= scene.lights.size())
      fail("{}: light = {}: the scene has {} light(s), indices 0 to {}", where, lightIndex, scene.lights.size(),
           static_cast<int>(scene.lights.size()) - 1);
    if (scene.lights[static_cast<size_t>(lightIndex)].isDirectional())
      for (int k = 0; k < frames; ++k)
        if (!(glm::length(pointAt(k)) > 1e-6f))
          fail(
              "{}: the light is directional, so the keys are directions towards it, and frame {} "
              "passes through the origin (no direction)",
              where, k);
  } else {
    // Every frame's camera must be a valid camera (not on its look_at point, up not along the view).
    for (int k = 0; k < frames; ++k) {
      Camera camera = scene.camera;
      camera.position = pointAt(k);
      try {
        camera.validate();
      } catch (const Error& e) {
        fail("{}: the camera at frame {}, at ({}, {}, {}): {}", where, k, camera.position.x, camera.position.y,
             camera.position.z, e.what());
      }
    }
  }
}

Vec3 Motion::pointAt(int frame) const {
  if (path.empty()) return Vec3(0.0f);
  if (frames < 2 || path.size() < 2) return path.front();
  std::vector<double> cumulative(path.size(), 0.0);
  for (size_t i = 1; i < path.size(); ++i)
    cumulative[i] = cumulative[i - 1] + glm::length(DVec3(path[i]) - DVec3(path[i - 1]));
  const double target = cumulative.back() * static_cast<double>(frame) / static_cast<double>(frames - 1);
  // The first and last frames are the keys themselves, bit for bit.
  if (frame <= 0) return path.front();
  if (frame >= frames - 1) return path.back();
  size_t i = 1;
  while (i + 1 < path.size() && cumulative[i] < target) ++i;
  const double span = cumulative[i] - cumulative[i - 1];
  const double t = span > 0.0 ? (target - cumulative[i - 1]) / span : 0.0;
  return Vec3(DVec3(path[i - 1]) + t * (DVec3(path[i]) - DVec3(path[i - 1])));
}

Light lightMovedTo(const Light& light, const Vec3& center) {
  const Vec3 offset = center - light.center();
  Light moved = [&] {
    switch (light.shape()) {
      case LightShape::Sphere:
        return Light::sphere(center, light.radius());
      case LightShape::Disk:
        return Light::disk(center, light.normal(), light.radius());
      case LightShape::Rect:
        return Light::rect(center, light.u(), light.v());
      case LightShape::Segment:
        return Light::segment(light.a() + offset, light.b() + offset);
      case LightShape::Polygon: {
        std::vector<Vec3> vertices = light.vertices();
        for (Vec3& v : vertices) v += offset;
        return Light::polygon(vertices);
      }
      case LightShape::Directional:
        return Light::directional(center, light.angularDiameter(), light.profile());
    }
    fail("light: unknown shape");
  }();
  moved.setIntensity(light.intensity());
  return moved;
}

Scene sceneAtFrame(const Scene& scene, const Motion& motion, int frame) {
  Scene s = scene;
  s.motion.reset();  // a frame is a still scene
  const Vec3 point = motion.pointAt(frame);
  if (motion.target == MotionTarget::Light) {
    Light& light = s.lights.at(static_cast<size_t>(motion.lightIndex));
    light = lightMovedTo(light, point);
  } else {
    s.camera.position = point;
  }
  return s;
}

}  // namespace penumbra
