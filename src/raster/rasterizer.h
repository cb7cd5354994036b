// The software triangle rasterizer behind renderGBuffer and renderLightMap (internal to
// penumbra_raster). It follows the classic homogeneous pipeline of the graphics APIs:
//
//  - Input triangles are given in clip space (x, y, z, w), OpenGL conventions: the visible volume is
//    -w <= x, y <= w, and the near plane is z >= -w. Triangles are clipped in clip space against the
//    near plane and against a guard band (|x|, |y| <= G w, G >= 2) that keeps raster coordinates in
//    range; vertices outside the guard band, behind the camera or non-finite never reach the raster
//    stage. There is no far plane: the depth test orders anything beyond it. A triangle with a
//    non-finite vertex is skipped (the scene loader rejects such input; here it must not crash).
//  - Raster space: pixel (x, y) covers [x, x+1) x [y, y+1), y grows downwards, and is sampled at its
//    centre (x + 0.5, y + 0.5) — the same sampling as Camera::generateRay. NDC maps to raster space
//    as X = (ndcX + 1) W / 2, Y = (1 - ndcY) H / 2. Vertices are snapped to 1/256 pixel
//    (8 sub-pixel bits, as Direct3D 11) and edge functions are evaluated exactly in 64-bit integers.
//  - Fill rule: top-left, as Direct3D and OpenGL. A sample exactly on an edge belongs to the triangle
//    only if that edge is a top edge (horizontal, the triangle below it) or a left edge. So a pixel
//    centre on an edge shared by two triangles belongs to exactly one of them: a mesh without gaps or
//    overlaps covers each pixel exactly once.
//  - No backface culling: both windings are drawn (shadow maps need the back faces, and the camera
//    G-buffer flips normals towards the camera instead).
//  - Depth test: less-than on the depth key z/w, interpolated linearly in raster space (exact for
//    any projective map). Callers choose what z means: the camera and perspective light maps use a
//    reversed, infinite-far key z = -zNear (so z/w = -zNear/w), whose float precision is relative
//    everywhere; orthographic maps use a linear key. Ties (equal keys) go to the triangle that comes
//    first in the input, so the output never depends on scheduling.
//  - Attributes: N floats per vertex, interpolated perspective-correctly. Interpolation is deferred:
//    after visibility is resolved, each pixel solves for the barycentrics of its winning (original,
//    unclipped) triangle from the homogeneous clip coordinates (Olano & Greer 1997, "Triangle scan
//    conversion using 2D homogeneous coordinates"), in double precision. The barycentrics are
//    clamped to the triangle (a pixel centre may lie up to 1/512 pixel outside it after snapping).
//  - Parallelism: triangles are set up and binned to 64x64 tiles in fixed-size chunks, and tiles are
//    rasterized independently with oneTBB. Chunks and tiles do not depend on the thread count and
//    each tile processes triangles in input order, so the output is bit-identical for any number of
//    threads.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <tbb/scalable_allocator.h>

#include "penumbra/image.h"
#include "penumbra/math.h"

namespace penumbra::raster {

// The per-call working arrays of the rasterizer and of its callers (flattened vertices, triangle
// setups, tile bins). oneTBB's scalable allocator keeps freed blocks of these sizes for the next
// call, where the C library returns them to the system and every frame faults its temporaries in
// afresh (a quarter of a light map's time on a machine with costly page faults).
template <class T>
using ScratchVector = std::vector<T, tbb::scalable_allocator<T>>;

inline constexpr int kSubpixelBits = 8;  //!< vertex snapping: 1/256 pixel
inline constexpr int kSubpixelScale = 1 << kSubpixelBits;
inline constexpr int kTileSize = 64;         //!< pixels per tile side
inline constexpr int kMaxImageSize = 16384;  //!< width and height, pixels

struct RasterInput {
  int width = 0;
  int height = 0;
  std::span<const Vec4> clipPositions;    //!< per vertex, clip space
  std::span<const glm::uvec3> triangles;  //!< vertex indices into clipPositions
  std::span<const int32_t> payloads;      //!< per triangle (object id, ...); empty: payload = -1
  int attributeCount = 0;                 //!< N floats per vertex
  std::span<const float> attributes;      //!< vertexCount * N, the N floats of a vertex together
  // Also keep, per pixel, the covering triangle with the largest depth key (the deepest surface),
  // handed to a TileVisitor as TileSamples::farTriangle: one pass for a map's near and far layers.
  bool farthestLayer = false;
  // With farthestLayer: per kTileSize tile (row-major, ceil(width / kTileSize) to a row), nonzero
  // where the far layer is wanted; empty: in every tile. A tile without it costs what a near-only
  // pass costs there (the far layer doubles the depth test's work and adds a resolve).
  std::span<const uint8_t> farthestTiles;
};

struct RasterOutput {
  Image<float> depth;                    //!< depth key z/w of the visible surface; kInfinity where empty
  Image<float> clipW;                    //!< clip w at the sample (perspective: view depth); kInfinity where empty
  Image<int32_t> triangle;               //!< index into RasterInput::triangles; -1 where empty
  Image<int32_t> payload;                //!< that triangle's payload; -1 where empty
  std::vector<Image<float>> attributes;  //!< N channels, perspective-correct; 0 where empty
};

// The resolved samples of one tile, handed to a TileVisitor: pixel (x0 + i, y0 + j) is entry
// j * kTileSize + i of each array, for i < width, j < height.
struct TileSamples {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  const int32_t* triangle = nullptr;   //!< input triangle index; -1 where empty
  const float* depth = nullptr;        //!< depth key; kInfinity where empty
  const Vec3* barycentrics = nullptr;  //!< perspective-correct, of the input triangle's vertices
  const float* clipW = nullptr;        //!< clip w at the sample
  // With RasterInput::farthestLayer, in the tiles it asks for (else nullptr): the covering triangle with the largest
  // depth key (the first in input order among equals) and its barycentrics, as above. (A depth taken back from the
  // interpolated key instead differs from the interpolated attribute by up to 1e-5 of it.)
  const int32_t* farTriangle = nullptr;
  const Vec3* farBarycentrics = nullptr;
};
// Called once per tile, concurrently for different tiles (it must only write that tile's pixels).
using TileVisitor = std::function<void(const TileSamples&)>;

// Rasterizes the triangles and hands every resolved tile to `visit`: for callers that build their
// own per-pixel products (the G-buffer) without intermediate images. Attributes are not used.
// Throws Error for an image size outside [1, kMaxImageSize], mismatched array sizes or a vertex
// index out of range.
void rasterize(const RasterInput& input, const TileVisitor& visit);

// Rasterizes the triangles into images (attributes interpolated with the barycentrics above).
RasterOutput rasterize(const RasterInput& input);

}  // namespace penumbra::raster
