// Scenes built in code for the raster tests: the primitives of include/penumbra/primitives.h placed
// on a ground plane (smooth and flat normals, closed and open meshes, several objects), and a
// closed room the camera or the light can stand inside.
#pragma once

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/primitives.h"
#include "penumbra/scene.h"

namespace penumbra::rastertest {

inline Object object(int32_t id, Mesh mesh, const Mat4& wsFromObject) {
  Object o;
  o.name = "object " + std::to_string(id);
  o.id = id;
  transformMesh(mesh, wsFromObject);
  o.mesh = std::move(mesh);
  return o;
}

// Ground plane, a smooth sphere, a flat box and a tilted torus; ids deliberately not 0..n-1.
inline Scene objectsScene() {
  Scene s;
  s.name = "raster-test-objects";
  s.source = "test scene";
  s.objects.push_back(object(1, makePlane(10.0f, 8.0f), Mat4(1.0f)));
  s.objects.push_back(object(2, makeSphere(1.0f, 24, 16), glm::translate(Mat4(1.0f), Vec3(0.0f, 1.0f, 0.0f))));
  s.objects.push_back(object(5, makeBox(Vec3(0.8f, 1.2f, 0.6f)),
                             glm::rotate(glm::translate(Mat4(1.0f), Vec3(2.2f, 0.6f, -1.0f)), 0.6f, Vec3(0, 1, 0))));
  s.objects.push_back(object(7, makeTorus(0.7f, 0.25f, 32, 12),
                             glm::rotate(glm::translate(Mat4(1.0f), Vec3(-2.2f, 0.8f, 0.6f)), 0.9f, Vec3(1, 0, 0.3f))));
  s.camera.position = Vec3(4.0f, 3.5f, 6.0f);
  s.camera.lookAt = Vec3(0.0f, 0.6f, 0.0f);
  s.camera.fovYDegrees = 45.0f;
  return s;
}

// A closed 8 x 3 x 6 room (a box seen from inside) with a sphere in it; the camera stands inside.
inline Scene roomScene() {
  Scene s;
  s.name = "raster-test-room";
  s.source = "test scene";
  s.objects.push_back(object(3, makeBox(Vec3(8.0f, 3.0f, 6.0f)), glm::translate(Mat4(1.0f), Vec3(0.0f, 1.5f, 0.0f))));
  s.objects.push_back(object(4, makeSphere(0.6f, 20, 12), glm::translate(Mat4(1.0f), Vec3(1.0f, 0.6f, -1.0f))));
  s.camera.position = Vec3(-3.0f, 1.6f, 2.2f);
  s.camera.lookAt = Vec3(2.0f, 0.4f, -1.5f);
  s.camera.fovYDegrees = 75.0f;
  return s;
}

}  // namespace penumbra::rastertest
