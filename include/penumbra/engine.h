// Running a technique inside an engine: the engine's own per-pixel buffers and its triangles in, V
// out, without penumbra's scene files or rasterizer (docs/architecture.md, "As a library"). The
// buffers are row-major arrays of width x height pixels of any size, row 0 at the top; they are read
// during the call only and copied into penumbra's layout.
//
//   Scene scene = makeScene(meshes, camera, light);
//   GBuffer gbuffer = makeGBuffer(buffers, camera, meshes);
//   technique->prepare(scene, scene.lights[0]);   // once per light change (maps, BVHs)
//   technique->visibility(gbuffer, v);             // every frame
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "penumbra/camera.h"
#include "penumbra/gbuffer.h"
#include "penumbra/light.h"
#include "penumbra/scene.h"

namespace penumbra {

// The engine's G-buffer: spans of width x height pixels (three floats a pixel for the vectors).
struct EngineGBuffer {
  int width = 0, height = 0;
  std::span<const float> wsPosition;         //!< xyz per pixel, world units
  std::span<const float> wsNormal;           //!< xyz per pixel, shading normal (any length; made unit)
  std::span<const int32_t> objectId;         //!< per pixel: the id of the EngineMesh seen, kNoObject (-1) if none
  std::span<const float> csDepth;            //!< optional (empty): view depth per pixel; else from the camera
  std::span<const float> wsGeometricNormal;  //!< optional (empty): face normal per pixel; else the shading normal
  // Without face normals, a technique's `horizon` takes the shading normal for the face's: `facing` then
  // finds no face turned from the light where the shading normal faces it, which is where its leaks are.
};

// One of the engine's meshes, in world space: an occluder, and a receiver where its id is in the
// G-buffer.
struct EngineMesh {
  int32_t id = 0;                     //!< >= 0, unique: the G-buffer's object id of its pixels
  std::span<const float> positions;   //!< xyz per vertex, world units
  std::span<const uint32_t> indices;  //!< three vertex indices per triangle
};

// A scene of the meshes, the camera and the light: what a technique's prepare() takes. Throws Error
// naming the mesh when an index is out of range, a position not finite, or an id negative or repeated.
Scene makeScene(const std::vector<EngineMesh>& meshes, const Camera& camera, const Light& light);

// penumbra's G-buffer from the engine's. Normals are made unit and turned towards the camera, as
// penumbra's own G-buffer has them. Throws Error naming the buffer, the pixel and what was expected:
// a buffer missing or of the wrong length, a size outside [1, 16384], an id that is no mesh's, a
// position, normal or depth that is not finite (a zero normal, a depth not above 0) where the pixel
// sees something.
GBuffer makeGBuffer(const EngineGBuffer& buffers, const Camera& camera, const std::vector<EngineMesh>& meshes);

}  // namespace penumbra
