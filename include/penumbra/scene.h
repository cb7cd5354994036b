// The scene model: triangle meshes grouped into objects (one object id per scene object, as the
// Brabec–Seidel paper groups polygons), a diffuse albedo per object, a pinhole camera, lights and
// the image size. All geometry is stored in world space.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "penumbra/camera.h"
#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/motion.h"
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

// A true sphere in world space. An object built from a `sphere` primitive whose transform keeps it
// a sphere (uniform scale, rotation, translation) remembers it, so a technique that handles spheres
// analytically (parker) can use it; every other technique uses the object's tessellated mesh,
// which is inscribed in it (its vertices lie on the sphere).
struct AnalyticSphere {
  Vec3 center{0.0f};
  float radius = 0.0f;  //!< world units, > 0
};

struct Object {
  std::string name;
  int32_t id = 0;  //!< object id, >= 0, unique in the scene
  Mesh mesh;
  Vec3 albedo{0.8f};
  std::optional<AnalyticSphere> sphere;  //!< set when the mesh tessellates this sphere
};

struct ImageSize {
  int width = 512;
  int height = 512;
};

// The largest camera image penumbra renders: each side in [1, kMaxImageSide] pixels and at most
// kMaxImagePixels pixels in all. The G-buffer alone takes 48 bytes per pixel (3.2 GB at the limit,
// 12.9 GB at 16384 x 16384), and V, the reference's standard error and the shaded image add about
// 20 more, so 16384 x 16384 is refused rather than left to run out of memory part way.
inline constexpr int kMaxImageSide = 16384;
inline constexpr int64_t kMaxImagePixels = int64_t{8192} * 8192;
// Throws Error "<where>: image size W x H ..." naming the limit that W x H breaks.
void checkImageSize(int width, int height, const std::string& where);

// What the techniques build from a scene's geometry alone (the Embree scene), kept with the scene
// (internal: src/core/scene_caches.h).
struct SceneCaches;
std::shared_ptr<SceneCaches> makeSceneCaches();

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
  // A light or the camera moving over a sequence of frames (the scene file's "motion"); absent: a
  // still scene.
  std::optional<Motion> motion;
  // The files the scene was read from (the scene file and its mesh files): outputs never replace them.
  std::vector<std::string> inputFiles;
  // Shared by every technique prepared on this scene or on a copy of it, so that one Embree scene
  // serves them all. Each use checks that the geometry is the one it was built from (every object's
  // id, positions and triangles, to the bit), so a changed mesh is never traced stale; null: each
  // technique builds its own.
  std::shared_ptr<SceneCaches> caches = makeSceneCaches();
  // The geometry's revision as its owner declares it. 0 (the default): undeclared, and every use of
  // `caches` proves the geometry unchanged by hashing every mesh (linear in the triangles: about 2 ms
  // a million). Otherwise a number from declareGeometry(), the owner's promise that every object's id,
  // positions and triangles are as they were when it was declared: a use that finds the caches built
  // from this revision proves nothing (a steady frame of a million triangles costs what one of a
  // thousand does). An owner that changes a mesh after declaring it declares again (or sets 0); one
  // that does not is traced against the old geometry. Copies share the revision with the caches.
  uint64_t geometryRevision = 0;
  // Declares the geometry as it is now: geometryRevision becomes a number that no other geometry
  // sharing `caches` has had (0 without caches).
  void declareGeometry();

  Bounds3 bounds() const;
  size_t triangleCount() const;
  // The object with this id, or nullptr.
  const Object* findObject(int32_t id) const;
};

}  // namespace penumbra
