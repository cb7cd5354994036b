// The scene model: triangle meshes grouped into objects (one object id per scene object, as the
// Brabec–Seidel paper groups polygons), a diffuse albedo per object, a pinhole camera, lights and
// the image size. All geometry is stored in world space.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "penumbra/camera.h"
#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/params.h"

namespace penumbra {

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  //!< per vertex shading normals; empty means flat (face) normals
  std::vector<glm::uvec3> triangles;

  size_t triangleCount() const { return triangles.size(); }
  Bounds3 bounds() const;
  // Geometric (face) normal of triangle i, unit length (zero for a degenerate triangle).
  Vec3 faceNormal(size_t i) const;
};

struct Object {
  std::string name;
  int32_t id = 0;  //!< object id, >= 0, unique in the scene
  Mesh mesh;
  Vec3 albedo{0.8f};
};

struct ImageSize {
  int width = 512;
  int height = 512;
};

struct Scene {
  std::string name;    //!< built-in name or file stem
  std::string source;  //!< where it came from ("built-in:torus" or a file path), for messages and reports
  std::vector<Object> objects;
  Camera camera;
  std::vector<Light> lights;
  ImageSize image;
  float ambient = 0.05f;  //!< ambient term of the shading, relative to the light's peak irradiance
  // Technique parameters given in the scene file ("techniques": {"pcss": {...}}), by technique name.
  std::map<std::string, ParamSet> techniqueParams;

  Bounds3 bounds() const;
  size_t triangleCount() const;
  // The object with this id, or nullptr.
  const Object* findObject(int32_t id) const;
};

}  // namespace penumbra
