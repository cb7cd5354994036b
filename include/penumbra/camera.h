// Pinhole camera. Camera space is right-handed and looks down -z (OpenGL convention); the view
// depth csDepth of a point is its distance along the viewing axis (-z in camera space).
// Raster space: pixel (x, y) covers [x, x+1) x [y, y+1), y grows downwards, and is sampled at its
// centre. generateRay() and clipFromCamera() * cameraFromWs() describe the same projection, so
// the rasterizer and the ray tracer see the same pixels.
#pragma once

#include "penumbra/math.h"

namespace penumbra {

struct Camera {
  Vec3 position{0.0f, 0.0f, 5.0f};
  Vec3 lookAt{0.0f};
  Vec3 up{0.0f, 1.0f, 0.0f};
  float fovYDegrees = 45.0f;  //!< full vertical field of view, degrees, in (0, 180)

  // Throws Error if position == lookAt, up is parallel to the view direction, or fov is out of range.
  void validate() const;

  Mat4 cameraFromWs() const;  //!< world -> camera (glm::lookAt)
  // Perspective projection for an image of the given aspect (width / height), OpenGL clip space.
  Mat4 clipFromCamera(float aspect, float zNear, float zFar) const;

  // The primary ray through raster position (px, py) of a width x height image (pixel centres at
  // integer + 0.5). Origin at the camera, direction not normalized: its camera-space z is -1, so
  // the ray parameter t of a hit equals the hit's view depth.
  Ray generateRay(float px, float py, int width, int height) const;

  // World -> homogeneous raster coordinates of a width x height image, generateRay's inverse: a world
  // point p maps to q = rasterFromWs * (p, 1) with raster position (q.x / q.w, q.y / q.w) and view
  // depth q.w (in front of the camera where q.w > 0); q.z carries no meaning.
  Mat4 rasterFromWs(int width, int height) const;
};

}  // namespace penumbra
