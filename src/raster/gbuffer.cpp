// renderGBuffer (include/penumbra/raster.h): the camera G-buffer by rasterization.
//
// The projection is the camera's own: Camera::cameraFromWs and the x/y rows of
// Camera::clipFromCamera, so pixel (x, y) sees what Camera::generateRay(x + 0.5, y + 0.5) sees, up
// to float rounding and the rasterizer's 1/256-pixel vertex snapping (which can only move
// silhouette pixels). The depth row is replaced by a reversed, infinite-far key (z_clip = -zNear,
// so the key -zNear / viewDepth keeps float's relative precision at every depth); zNear is fitted to
// the scene bounds: just in front of the nearest bounds corner when the camera is outside the
// bounds, so nothing in front of the camera is lost, and 1e-6 of the farthest corner's depth when
// the camera is inside them (only geometry closer than that is clipped).
//
// Per pixel: world position and shading normal interpolated perspective-correctly (vertex normals
// where the mesh has one per vertex, else the face normal), the face normal, object and triangle
// id, and the view depth (clip w). Both normals are turned towards the camera together, following
// the geometric normal (as traceGBuffer does), so that at a smooth silhouette, where the
// interpolated normal may lean slightly away, it still describes the visible side.
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "penumbra/error.h"
#include "penumbra/raster.h"
#include "rasterizer.h"

namespace penumbra {
namespace {

// The camera's projection fitted to the scene bounds (see the file comment): clipFromCamera's x/y
// rows with the reversed, infinite-far depth key, times cameraFromWs. Empty when the whole scene
// lies behind the camera.
std::optional<Mat4> fittedClipFromWs(const Camera& camera, const Bounds3& bounds, int width, int height) {
  const Mat4 cameraFromWs = camera.cameraFromWs();
  float minDepth = kInfinity, maxDepth = -kInfinity;
  for (int i = 0; i < 8; ++i) {
    const Vec3 corner((i & 1) ? bounds.upper.x : bounds.lower.x, (i & 2) ? bounds.upper.y : bounds.lower.y,
                      (i & 4) ? bounds.upper.z : bounds.lower.z);
    const float depth = -(cameraFromWs * Vec4(corner, 1.0f)).z;
    minDepth = std::min(minDepth, depth);
    maxDepth = std::max(maxDepth, depth);
  }
  if (!(maxDepth > 0.0f)) return std::nullopt;  // the whole scene is behind the camera
  const float zNear = std::max(minDepth * 0.999f, maxDepth * 1e-6f);
  const float zFar = std::max(maxDepth * 1.001f, zNear * 2.0f);  // only for clipFromCamera's x/y rows
  Mat4 clipFromCamera = camera.clipFromCamera(static_cast<float>(width) / static_cast<float>(height), zNear, zFar);
  clipFromCamera[2][2] = 0.0f;  // z_clip = -zNear: reversed, infinite-far depth key
  clipFromCamera[3][2] = -zNear;
  return clipFromCamera * cameraFromWs;
}

// The scene flattened for the rasterizer: one vertex array, triangles indexing into it, and per
// triangle its object's index and face normal (computed once per triangle rather than per pixel).
struct FlatScene {
  std::vector<size_t> firstVertex, firstTriangle;  //!< per object: where its vertices and triangles start
  raster::ScratchVector<Vec4> clip;
  raster::ScratchVector<glm::uvec3> triangles;
  raster::ScratchVector<int32_t> objectIndex;
  raster::ScratchVector<Vec3> faceNormals;
};

void flattenScene(const Scene& scene, const Mat4& clipFromWs, FlatScene& flat) {
  size_t vertexCount = 0, triangleCount = 0;
  for (const Object& object : scene.objects) {
    flat.firstVertex.push_back(vertexCount);
    flat.firstTriangle.push_back(triangleCount);
    vertexCount += object.mesh.positions.size();
    triangleCount += object.mesh.triangleCount();
  }
  flat.clip.resize(vertexCount);
  flat.triangles.resize(triangleCount);
  flat.objectIndex.resize(triangleCount);
  flat.faceNormals.resize(triangleCount);
  // Split within objects too: one large mesh would otherwise be one serial task.
  tbb::parallel_for(size_t(0), scene.objects.size(), [&](size_t o) {
    const Mesh& mesh = scene.objects[o].mesh;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.positions.size(), 8192),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i < r.end(); ++i)
                          flat.clip[flat.firstVertex[o] + i] = clipFromWs * Vec4(mesh.positions[i], 1.0f);
                      });
    const auto offset = static_cast<uint32_t>(flat.firstVertex[o]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.triangles.size(), 8192),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t t = r.begin(); t < r.end(); ++t) {
                          flat.triangles[flat.firstTriangle[o] + t] = mesh.triangles[t] + glm::uvec3(offset);
                          flat.objectIndex[flat.firstTriangle[o] + t] = static_cast<int32_t>(o);
                          flat.faceNormals[flat.firstTriangle[o] + t] = mesh.faceNormal(t);
                        }
                      });
  });
}

// Everything a pixel needs from its triangle, gathered once per run of pixels that share it (a
// tile's row mostly crosses few triangles), so the per-pixel work is interpolation and stores.
struct TriangleData {
  Vec3 p0{0.0f}, p1{0.0f}, p2{0.0f};  // world positions
  Vec3 n0{0.0f}, n1{0.0f}, n2{0.0f};  // vertex normals (when hasNormals)
  Vec3 faceNormal{0.0f};
  int32_t objectId = kNoObject, localTriangle = -1;
  bool hasNormals = false;
};

void gatherTriangle(const Scene& scene, const FlatScene& flat, int32_t triangle, TriangleData& d) {
  const auto o = static_cast<size_t>(flat.objectIndex[static_cast<size_t>(triangle)]);
  const Object& object = scene.objects[o];
  const Mesh& mesh = object.mesh;
  const size_t local = static_cast<size_t>(triangle) - flat.firstTriangle[o];
  const glm::uvec3& t = mesh.triangles[local];
  d.p0 = mesh.positions[t.x];
  d.p1 = mesh.positions[t.y];
  d.p2 = mesh.positions[t.z];
  d.hasNormals = !mesh.normals.empty() && mesh.normals.size() == mesh.positions.size();
  if (d.hasNormals) {
    d.n0 = mesh.normals[t.x];
    d.n1 = mesh.normals[t.y];
    d.n2 = mesh.normals[t.z];
  }
  d.faceNormal = flat.faceNormals[static_cast<size_t>(triangle)];
  d.objectId = object.id;
  d.localTriangle = static_cast<int32_t>(local);
}

// One resolved tile into the G-buffer: straight from the rasterizer, no intermediate attribute images.
void writeTile(const Scene& scene, const FlatScene& flat, const raster::TileSamples& samples, GBuffer& g) {
  int32_t cached = -1;
  TriangleData d;
  for (int j = 0; j < samples.height; ++j) {
    const int y = samples.y0 + j;
    Vec3* wsPosition = g.wsPosition.row(y) + samples.x0;
    Vec3* wsNormal = g.wsNormal.row(y) + samples.x0;
    Vec3* wsGeometricNormal = g.wsGeometricNormal.row(y) + samples.x0;
    int32_t* objectId = g.objectId.row(y) + samples.x0;
    int32_t* triangleId = g.triangleId.row(y) + samples.x0;
    float* csDepth = g.csDepth.row(y) + samples.x0;
    for (int i = 0; i < samples.width; ++i) {
      const int k = j * raster::kTileSize + i;
      const int32_t triangle = samples.triangle[k];
      if (triangle < 0) {  // resetGBuffer's values
        wsPosition[i] = Vec3(0.0f);
        wsNormal[i] = Vec3(0.0f);
        wsGeometricNormal[i] = Vec3(0.0f);
        objectId[i] = kNoObject;
        triangleId[i] = -1;
        csDepth[i] = kInfinity;
        continue;
      }
      if (triangle != cached) {
        gatherTriangle(scene, flat, triangle, d);
        cached = triangle;
      }
      const Vec3& b = samples.barycentrics[k];
      const Vec3 wsP = b.x * d.p0 + b.y * d.p1 + b.z * d.p2;
      Vec3 ng = d.faceNormal;
      Vec3 ns = ng;
      if (d.hasNormals) {
        const Vec3 n = b.x * d.n0 + b.y * d.n1 + b.z * d.n2;
        const float len = glm::length(n);
        if (len > 0.0f && std::isfinite(len)) ns = n / len;
      }
      // Both normals follow the geometric one towards the camera (file comment).
      if (glm::dot(ng, wsP - scene.camera.position) > 0.0f) {
        ng = -ng;
        ns = -ns;
      }
      wsPosition[i] = wsP;
      wsNormal[i] = ns;
      wsGeometricNormal[i] = ng;
      objectId[i] = d.objectId;
      triangleId[i] = d.localTriangle;
      csDepth[i] = samples.clipW[k];
    }
  }
}

}  // namespace

GBuffer renderGBuffer(const Scene& scene, int width, int height) {
  GBuffer g;
  renderGBuffer(scene, width, height, g);
  return g;
}

// Its six images filled concurrently: at 1024 x 1024 they are 48 MB, whose fill (and, the first time,
// page faults: about a fifth of the pass's CPU time in the benchmark, measured with perf) would
// otherwise run on the calling thread alone. Images keep their storage where it is large enough.
void resetGBuffer(GBuffer& g, int width, int height) {
  tbb::parallel_invoke(
      [&] { g.wsPosition.reset(width, height, Vec3(0.0f)); }, [&] { g.wsNormal.reset(width, height, Vec3(0.0f)); },
      [&] { g.wsGeometricNormal.reset(width, height, Vec3(0.0f)); },
      [&] { g.objectId.reset(width, height, kNoObject); }, [&] { g.triangleId.reset(width, height, -1); },
      [&] { g.csDepth.reset(width, height, kInfinity); });
}

void renderGBuffer(const Scene& scene, int width, int height, GBuffer& g) {
  checkImageSize(width, height, "renderGBuffer");
  scene.camera.validate();
  const Bounds3 bounds = scene.bounds();
  const std::optional<Mat4> clipFromWs =
      bounds.empty() ? std::nullopt : fittedClipFromWs(scene.camera, bounds, width, height);
  if (!clipFromWs) {  // nothing in view
    resetGBuffer(g, width, height);
    return;
  }
  // The rasterizer visits every tile and writeTile writes every pixel of it, an empty one as the
  // empty G-buffer holds it: no fill first (and a fresh image's pages are first touched by the tiles'
  // threads).
  g.wsPosition.resizeForOverwrite(width, height);
  g.wsNormal.resizeForOverwrite(width, height);
  g.wsGeometricNormal.resizeForOverwrite(width, height);
  g.objectId.resizeForOverwrite(width, height);
  g.triangleId.resizeForOverwrite(width, height);
  g.csDepth.resizeForOverwrite(width, height);
  FlatScene flat;
  flattenScene(scene, *clipFromWs, flat);
  raster::RasterInput input;
  input.width = width;
  input.height = height;
  input.clipPositions = flat.clip;
  input.triangles = flat.triangles;
  raster::rasterize(input, [&](const raster::TileSamples& samples) { writeTile(scene, flat, samples, g); });
}

}  // namespace penumbra
