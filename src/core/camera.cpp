#include "penumbra/camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"

namespace penumbra {

void Camera::validate() const {
  if (!isFinite(position) || !isFinite(lookAt) || !isFinite(up))
    fail("camera: position, look_at and up must be finite");
  const Vec3 forward = lookAt - position;
  if (!(glm::length(forward) > 0.0f)) fail("camera: look_at must differ from position");
  if (!(glm::length(up) > 0.0f)) fail("camera: up must be a non-zero vector");
  if (glm::length(glm::cross(glm::normalize(forward), glm::normalize(up))) < 1e-4f)
    fail("camera: up must not be parallel to the viewing direction (look_at - position)");
  if (!(fovYDegrees > 0.0f && fovYDegrees < 180.0f))
    fail("camera: fov_y must be in (0, 180) degrees (got {})", fovYDegrees);
}

Mat4 Camera::cameraFromWs() const { return glm::lookAt(position, lookAt, up); }

Mat4 Camera::clipFromCamera(float aspect, float zNear, float zFar) const {
  return glm::perspective(radians(fovYDegrees), aspect, zNear, zFar);
}

Ray Camera::generateRay(float px, float py, int width, int height) const {
  const float tanHalf = std::tan(0.5f * radians(fovYDegrees));
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  const float ndcX = 2.0f * px / static_cast<float>(width) - 1.0f;
  const float ndcY = 1.0f - 2.0f * py / static_cast<float>(height);
  const Vec3 csDirection(ndcX * tanHalf * aspect, ndcY * tanHalf, -1.0f);
  // Camera-space axes in world space: the rows of the rotation part of cameraFromWs.
  const Vec3 f = glm::normalize(lookAt - position);
  const Vec3 s = glm::normalize(glm::cross(f, up));
  const Vec3 u = glm::cross(s, f);
  Ray ray;
  ray.origin = position;
  ray.direction = csDirection.x * s + csDirection.y * u - csDirection.z * f;
  return ray;
}

Mat4 Camera::rasterFromWs(int width, int height) const {
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  // The viewport of generateRay: x = (ndc_x + 1) w / 2, y = (1 - ndc_y) h / 2, applied before the
  // division by clip w (it is affine in clip space). Near and far only set the z row, unused here.
  Mat4 viewport(1.0f);
  viewport[0][0] = 0.5f * w;
  viewport[3][0] = 0.5f * w;
  viewport[1][1] = -0.5f * h;
  viewport[3][1] = 0.5f * h;
  return viewport * clipFromCamera(w / h, 1.0f, 2.0f) * cameraFromWs();
}

}  // namespace penumbra
