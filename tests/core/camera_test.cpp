// Tests of the pinhole camera (src/core/camera.cpp): a primary ray's parameter t equals the view depth
// of the point it reaches, the centre pixel looks along the view axis, generateRay agrees with the
// projection matrices (the rasterizer's view) and rasterFromWs inverts it, and invalid cameras are
// rejected.
#include <gtest/gtest.h>

#include "penumbra/camera.h"
#include "penumbra/error.h"

namespace penumbra {
namespace {

Camera testCamera() {
  Camera c;
  c.position = Vec3(1.0f, 2.0f, 6.0f);
  c.lookAt = Vec3(-0.5f, 0.3f, 0.0f);
  c.up = Vec3(0, 1, 0);
  c.fovYDegrees = 50.0f;
  return c;
}

TEST(Camera, RayParameterIsTheViewDepth) {
  const Camera cam = testCamera();
  const Mat4 cameraFromWs = cam.cameraFromWs();
  for (const Vec2 px : {Vec2(0.5f, 0.5f), Vec2(63.5f, 10.5f), Vec2(20.25f, 47.75f)}) {
    const Ray ray = cam.generateRay(px.x, px.y, 64, 48);
    EXPECT_EQ(ray.origin, cam.position);
    for (const float t : {0.5f, 3.0f, 10.0f}) {
      const Vec3 wsP = ray.origin + t * ray.direction;
      const Vec4 csP = cameraFromWs * Vec4(wsP, 1.0f);
      EXPECT_NEAR(-csP.z, t, 1e-4f * t);  // view depth: distance along -z in camera space
    }
  }
}

TEST(Camera, CentrePixelLooksAlongTheViewAxis) {
  const Camera cam = testCamera();
  // Odd sizes have a pixel whose centre is the image centre.
  const Ray ray = cam.generateRay(2.5f, 1.5f, 5, 3);
  const Vec3 axis = glm::normalize(cam.lookAt - cam.position);
  EXPECT_NEAR(glm::length(ray.direction - axis), 0.0f, 1e-6f);
}

TEST(Camera, RaysMatchTheProjectionMatrices) {
  const Camera cam = testCamera();
  const int w = 64, h = 48;
  const Mat4 clipFromWs = cam.clipFromCamera(static_cast<float>(w) / h, 0.1f, 100.0f) * cam.cameraFromWs();
  for (const Vec2 px : {Vec2(0.5f, 0.5f), Vec2(63.5f, 47.5f), Vec2(10.5f, 30.5f), Vec2(32.0f, 24.0f)}) {
    const Ray ray = cam.generateRay(px.x, px.y, w, h);
    const Vec4 clip = clipFromWs * Vec4(ray.origin + 4.0f * ray.direction, 1.0f);
    const float sx = (clip.x / clip.w * 0.5f + 0.5f) * w;
    const float sy = (0.5f - clip.y / clip.w * 0.5f) * h;  // raster y grows downwards
    EXPECT_NEAR(sx, px.x, 1e-3f);
    EXPECT_NEAR(sy, px.y, 1e-3f);
  }
  // Top-left pixel looks up and to the left.
  const Ray topLeft = cam.generateRay(0.5f, 0.5f, w, h);
  const Vec4 cs = cam.cameraFromWs() * Vec4(cam.position + topLeft.direction, 1.0f);
  EXPECT_LT(cs.x, 0.0f);
  EXPECT_GT(cs.y, 0.0f);
}

// rasterFromWs undoes generateRay: a point on the ray through (px, py) maps back to (px, py), with its
// view depth (the ray parameter) as w; a point behind the camera has w < 0.
TEST(Camera, RasterFromWsInvertsGenerateRay) {
  const Camera cam = testCamera();
  const int w = 64, h = 48;
  const Mat4 rasterFromWs = cam.rasterFromWs(w, h);
  for (const Vec2 px : {Vec2(0.5f, 0.5f), Vec2(63.5f, 47.5f), Vec2(10.25f, 30.75f), Vec2(32.0f, 24.0f)})
    for (const float t : {0.5f, 4.0f, 30.0f}) {
      const Ray ray = cam.generateRay(px.x, px.y, w, h);
      const Vec4 q = rasterFromWs * Vec4(ray.origin + t * ray.direction, 1.0f);
      EXPECT_NEAR(q.x / q.w, px.x, 1e-3f);
      EXPECT_NEAR(q.y / q.w, px.y, 1e-3f);
      EXPECT_NEAR(q.w, t, 1e-4f * t);
    }
  const Vec4 behind = rasterFromWs * Vec4(cam.position - (cam.lookAt - cam.position), 1.0f);
  EXPECT_LT(behind.w, 0.0f);
}

TEST(Camera, ValidateRejectsBadCameras) {
  EXPECT_NO_THROW(testCamera().validate());
  Camera c = testCamera();
  c.lookAt = c.position;
  EXPECT_THROW(c.validate(), Error);
  c = testCamera();
  c.up = glm::normalize(c.lookAt - c.position);
  EXPECT_THROW(c.validate(), Error);
  c = testCamera();
  c.up = Vec3(0.0f);
  EXPECT_THROW(c.validate(), Error);
  for (const float fov : {0.0f, 180.0f, -5.0f, std::nanf("")}) {
    c = testCamera();
    c.fovYDegrees = fov;
    EXPECT_THROW(c.validate(), Error) << fov;
  }
  c = testCamera();
  c.position.x = kInfinity;
  EXPECT_THROW(c.validate(), Error);
}

}  // namespace
}  // namespace penumbra
