// Motion (include/penumbra/motion.h): frames walk the path at constant speed by arc length, the
// first and last frames are the path's ends exactly, every light shape moves as a rigid body (its
// size and orientation kept), the camera keeps its target, and bad motions are refused naming the
// field.
#include <string>

#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/motion.h"
#include "penumbra/scene.h"

namespace penumbra {
namespace {

Scene sceneWith(const Light& light) {
  Scene scene;
  scene.camera.position = Vec3(0.0f, 2.0f, 5.0f);
  scene.camera.lookAt = Vec3(0.0f);
  scene.lights.push_back(light);
  return scene;
}

std::string errorOf(const Motion& motion, const Scene& scene) {
  try {
    motion.validate(scene, "x.json: motion");
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an error";
  return "";
}

TEST(Motion, FramesWalkThePathAtConstantSpeed) {
  Motion m;
  // Two legs, of lengths 1 and 3: frame k of 5 lies k/4 of the total 4 along.
  m.path = {Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(1.0f, 3.0f, 0.0f)};
  m.frames = 5;
  EXPECT_EQ(m.pointAt(0), m.path.front());
  EXPECT_EQ(m.pointAt(4), m.path.back());
  const Vec3 expected[] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(1, 2, 0), Vec3(1, 3, 0)};
  for (int k = 0; k < 5; ++k)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(m.pointAt(k)[c], expected[k][c], 1e-6f) << "frame " << k;
}

TEST(Motion, EveryLightShapeMovesAsARigidBody) {
  const Vec3 to(0.3f, 4.2f, -0.1f);
  const Light lights[] = {
      Light::sphere(Vec3(0, 4, 0), 0.5f),
      Light::disk(Vec3(0, 4, 0), Vec3(0.2f, -1, 0), 0.5f),
      Light::rect(Vec3(0, 4, 0), Vec3(0.5f, 0, 0), Vec3(0, 0, 0.25f)),
      Light::segment(Vec3(-1, 4, 0), Vec3(1, 4, 0.5f)),
      Light::polygon(
          {Vec3(0, 4, 0), Vec3(1, 4, 0), Vec3(1, 4, 1), Vec3(0.5f, 4, 1), Vec3(0.5f, 4, 0.5f), Vec3(0, 4, 0.5f)}),
  };
  for (const Light& light : lights) {
    Light l = light;
    l.setIntensity(2.5f);
    const Light moved = lightMovedTo(l, to);
    const std::string shape(toString(l.shape()));
    EXPECT_EQ(moved.shape(), l.shape()) << shape;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(moved.center()[c], to[c], 1e-5f) << shape;
    EXPECT_NEAR(moved.extent(), l.extent(), 1e-5f) << shape;
    EXPECT_NEAR(moved.area(), l.area(), 1e-5f) << shape;
    EXPECT_EQ(moved.intensity(), 2.5f) << shape;
    const Vec3 offset = to - l.center();
    for (size_t i = 0; i < l.vertices().size(); ++i)
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(moved.vertices()[i][c], l.vertices()[i][c] + offset[c], 1e-5f) << shape;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(moved.normal()[c], l.normal()[c], 1e-6f) << shape;
  }
  const Light sun = Light::directional(Vec3(0, 1, 0), 0.1f, LightProfile::LimbDarkened);
  const Light turned = lightMovedTo(sun, Vec3(0, 2, 2));
  EXPECT_NEAR(turned.direction().y, std::sqrt(0.5f), 1e-6f);
  EXPECT_NEAR(turned.direction().z, std::sqrt(0.5f), 1e-6f);
  EXPECT_EQ(turned.angularDiameter(), sun.angularDiameter());
  EXPECT_EQ(turned.profile(), LightProfile::LimbDarkened);
}

TEST(Motion, AFrameIsAStillSceneWithOnlyTheMovingPartChanged) {
  Scene scene = sceneWith(Light::sphere(Vec3(0, 4, 0), 0.5f));
  scene.lights.push_back(Light::disk(Vec3(2, 4, 0), Vec3(0, -1, 0), 0.3f));
  Motion m;
  m.lightIndex = 1;
  m.path = {Vec3(2, 4, 0), Vec3(2.2f, 4, 0)};
  m.frames = 3;
  m.validate(scene, "test");
  scene.motion = m;
  const Scene frame = sceneAtFrame(scene, m, 1);
  EXPECT_FALSE(frame.motion.has_value());
  EXPECT_EQ(frame.lights[0].center(), scene.lights[0].center());
  EXPECT_NEAR(frame.lights[1].center().x, 2.1f, 1e-6f);
  EXPECT_EQ(frame.camera.position, scene.camera.position);

  Motion camera;
  camera.target = MotionTarget::Camera;
  camera.path = {Vec3(0, 2, 5), Vec3(1, 2, 5)};
  camera.frames = 2;
  camera.validate(scene, "test");
  const Scene last = sceneAtFrame(scene, camera, 1);
  EXPECT_EQ(last.camera.position, Vec3(1, 2, 5));
  EXPECT_EQ(last.camera.lookAt, scene.camera.lookAt);
  EXPECT_EQ(last.lights[1].center(), scene.lights[1].center());
}

TEST(Motion, BadMotionsAreRefusedNamingTheField) {
  const Scene scene = sceneWith(Light::sphere(Vec3(0, 4, 0), 0.5f));
  Motion m;
  m.path = {Vec3(0, 4, 0)};
  EXPECT_NE(errorOf(m, scene).find("x.json: motion: path has 1 key point(s): expected at least 2"), std::string::npos);
  m.path = {Vec3(0, 4, 0), Vec3(0, 4, 0)};
  EXPECT_NE(errorOf(m, scene).find("zero length"), std::string::npos);
  m.path = {Vec3(0, 4, 0), Vec3(0, std::nanf(""), 0)};
  EXPECT_NE(errorOf(m, scene).find("key 1 is not finite"), std::string::npos);
  m.path = {Vec3(0, 4, 0), Vec3(1, 4, 0)};
  m.frames = 1;
  EXPECT_NE(errorOf(m, scene).find("x.json: motion: frames = 1: expected an int in [2, 1000]"), std::string::npos);
  m.frames = 4;
  m.lightIndex = 1;
  EXPECT_NE(errorOf(m, scene).find("x.json: motion: light = 1: the scene has 1 light(s)"), std::string::npos);

  const Scene sunny = sceneWith(Light::directional(Vec3(0, 1, 0), 0.1f));
  Motion sun;
  sun.path = {Vec3(-1, 0, 0), Vec3(1, 0, 0)};
  sun.frames = 3;  // the middle frame's direction is (0, 0, 0)
  EXPECT_NE(errorOf(sun, sunny).find("frame 1 passes through the origin"), std::string::npos);

  Motion camera;
  camera.target = MotionTarget::Camera;
  camera.path = {Vec3(0, 2, 5), Vec3(0, 2, -5)};
  camera.frames = 3;  // the middle frame sits on the look_at point
  EXPECT_NE(errorOf(camera, scene).find("x.json: motion: the camera at frame 1"), std::string::npos);
}

}  // namespace
}  // namespace penumbra
