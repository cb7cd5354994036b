// The software triangle rasterizer: clipping, snapping, top-left edge functions, tiled depth test
// and deferred perspective-correct attribute interpolation. The conventions (raster space, fill
// rule, depth key, guard band, determinism) are documented in rasterizer.h.
//
// Stages, each parallel with oneTBB:
//  1. vertices: outcodes, and for vertices inside the guard band their snapped raster position and
//     depth key (computed once per vertex, so triangles sharing a vertex share its exact position);
//  2. triangles, in fixed chunks of kChunkTriangles: trivial reject, clipping where needed,
//     integer setup, and binning of the setups to tiles (a counting sort per chunk);
//  3. tiles: for every chunk in order, the tile's triangles in order are rasterized into a
//     tile-local depth + winner buffer; then each covered pixel is resolved (barycentrics,
//     clip w, attributes) once, against its winning triangle.
#include "rasterizer.h"

#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "penumbra/error.h"

namespace penumbra::raster {
namespace {

constexpr size_t kChunkTriangles = 4096;

// Outcode bits of a clip-space vertex against the viewport planes (for trivial rejection) and the
// conditions that force a triangle through the clipper.
enum : uint8_t {
  kOutLeft = 1,    // x < -w
  kOutRight = 2,   // x > w
  kOutBottom = 4,  // y < -w
  kOutTop = 8,     // y > w
  kOutNear = 16,   // z < -w
  kNonFinite = 32,
  kNeedsClip = 64,  // behind the near plane, w <= 0 or outside the guard band
};
constexpr uint8_t kRejectMask = kOutLeft | kOutRight | kOutBottom | kOutTop | kOutNear;

// A vertex in raster space: position in 1/kSubpixelScale pixels, depth key z/w.
struct RasterVertex {
  int32_t x, y;
  float key;
};

// One triangle ready for rasterization: snapped vertices ordered so that the three edge functions
// are >= 0 inside, its pixel bounding box (inclusive, within the image) and its depth-key plane.
struct Setup {
  std::array<int32_t, 3> x, y;
  int32_t xMin, yMin, xMax, yMax;
  float key0;          // depth key at vertex 0
  float keyDx, keyDy;  // per pixel in x and y
  int32_t triangle;    // input triangle index
};

struct Chunk {
  ScratchVector<Setup> setups;
  ScratchVector<uint32_t> tileStart;  // items of tile t: items[tileStart[t], tileStart[t+1])
  ScratchVector<uint32_t> items;      // indices into setups, in input order within each tile
};

struct Context {
  int width, height;
  int tilesX, tilesY;
  double guardBand;  // G: clip planes |x|, |y| <= G w
};

uint8_t outcode(const Vec4& c, double guardBand) {
  if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || !std::isfinite(c.w)) return kNonFinite;
  uint8_t code = 0;
  if (c.x < -c.w) code |= kOutLeft;
  if (c.x > c.w) code |= kOutRight;
  if (c.y < -c.w) code |= kOutBottom;
  if (c.y > c.w) code |= kOutTop;
  if (c.z < -c.w) code |= kOutNear;
  const double gw = guardBand * static_cast<double>(c.w);
  if ((code & kOutNear) || !(c.w > 0.0f) || std::abs(static_cast<double>(c.x)) > gw ||
      std::abs(static_cast<double>(c.y)) > gw)
    code |= kNeedsClip;
  return code;
}

// Clip space -> raster space. Only called for vertices inside the guard band with w > 0, where the
// snapped coordinates stay below 2^23 in magnitude (see guardBandFor), so edge functions fit in
// 64 bits with room to spare.
RasterVertex toRaster(const Vec4& c, const Context& ctx) {
  const double invW = 1.0 / static_cast<double>(c.w);
  const double ndcX = static_cast<double>(c.x) * invW;
  const double ndcY = static_cast<double>(c.y) * invW;
  RasterVertex v;
  v.x = static_cast<int32_t>(std::lrint((ndcX * 0.5 + 0.5) * ctx.width * kSubpixelScale));
  v.y = static_cast<int32_t>(std::lrint((0.5 - ndcY * 0.5) * ctx.height * kSubpixelScale));
  v.key = static_cast<float>(static_cast<double>(c.z) * invW);
  return v;
}

// G such that (G + 1) / 2 * max(width, height) * kSubpixelScale < 2^23.
double guardBandFor(int width, int height) {
  const int maxSize = std::max(width, height);
  return std::max(2.0, 32768.0 / maxSize - 1.0);
}

// Floor and ceiling division by kSubpixelScale (arithmetic shift floors negative values in C++20).
int32_t floorSub(int64_t v) { return static_cast<int32_t>(v >> kSubpixelBits); }
int32_t ceilSub(int64_t v) { return static_cast<int32_t>((v + kSubpixelScale - 1) >> kSubpixelBits); }

void setupTriangle(RasterVertex v0, RasterVertex v1, RasterVertex v2, int32_t triangle, const Context& ctx,
                   ScratchVector<Setup>& out) {
  int64_t area = static_cast<int64_t>(v1.x - v0.x) * (v2.y - v0.y) - static_cast<int64_t>(v1.y - v0.y) * (v2.x - v0.x);
  if (area == 0) return;  // degenerate after snapping: covers no sample
  if (area < 0) {         // no culling: reorder so that the edge functions are positive inside
    std::swap(v1, v2);
    area = -area;
  }
  const int64_t half = kSubpixelScale / 2;
  // Pixel x is a candidate when its centre x*S + S/2 lies within [minX, maxX].
  Setup s;
  s.xMin = std::max(0, ceilSub(static_cast<int64_t>(std::min({v0.x, v1.x, v2.x})) - half));
  s.xMax = std::min(ctx.width - 1, floorSub(static_cast<int64_t>(std::max({v0.x, v1.x, v2.x})) - half));
  s.yMin = std::max(0, ceilSub(static_cast<int64_t>(std::min({v0.y, v1.y, v2.y})) - half));
  s.yMax = std::min(ctx.height - 1, floorSub(static_cast<int64_t>(std::max({v0.y, v1.y, v2.y})) - half));
  if (s.xMin > s.xMax || s.yMin > s.yMax) return;
  s.x = {v0.x, v1.x, v2.x};
  s.y = {v0.y, v1.y, v2.y};
  // Depth-key plane through the snapped vertices, per pixel, relative to vertex 0.
  const double inv = 1.0 / kSubpixelScale;
  const double dx1 = (v1.x - v0.x) * inv, dy1 = (v1.y - v0.y) * inv;
  const double dx2 = (v2.x - v0.x) * inv, dy2 = (v2.y - v0.y) * inv;
  const double dz1 = static_cast<double>(v1.key) - v0.key, dz2 = static_cast<double>(v2.key) - v0.key;
  const double det = static_cast<double>(area) * inv * inv;
  s.key0 = v0.key;
  s.keyDx = static_cast<float>((dz1 * dy2 - dz2 * dy1) / det);
  s.keyDy = static_cast<float>((dx1 * dz2 - dx2 * dz1) / det);
  s.triangle = triangle;
  out.push_back(s);
}

// Sutherland-Hodgman clipping of a convex clip-space polygon against the plane dot(plane, c) >= 0.
// The intersection on an edge is always computed from its inside end to its outside end, so two
// triangles sharing an edge produce bit-identical new vertices on it and stay watertight.
int clipPolygon(const Vec4* in, int count, const DVec3& planeXYW, double planeZ, Vec4* out) {
  auto distance = [&](const Vec4& c) { return planeXYW.x * c.x + planeXYW.y * c.y + planeXYW.z * c.w + planeZ * c.z; };
  int n = 0;
  for (int i = 0; i < count; ++i) {
    const Vec4& a = in[i];
    const Vec4& b = in[(i + 1) % count];
    const double da = distance(a), db = distance(b);
    if (da >= 0.0) out[n++] = a;
    if ((da >= 0.0) != (db >= 0.0)) {
      const Vec4& inside = da >= 0.0 ? a : b;
      const Vec4& outside = da >= 0.0 ? b : a;
      const double dIn = da >= 0.0 ? da : db, dOut = da >= 0.0 ? db : da;
      const double t = dIn / (dIn - dOut);
      out[n++] = Vec4(glm::dvec4(inside) + t * (glm::dvec4(outside) - glm::dvec4(inside)));
    }
  }
  return n;
}

// Clips a triangle against the near plane and the guard band, then sets up its fan.
void clipAndSetup(const Vec4& c0, const Vec4& c1, const Vec4& c2, int32_t triangle, const Context& ctx,
                  ScratchVector<Setup>& out) {
  // A triangle gains at most one vertex per plane: 3 + 5.
  std::array<Vec4, 9> a{c0, c1, c2}, b{};
  int n = 3;
  const double g = ctx.guardBand;
  // Planes as (coefficients of x, y, w), coefficient of z.
  const std::array<std::pair<DVec3, double>, 5> planes{{
      {DVec3(0.0, 0.0, 1.0), 1.0},  // near: z + w >= 0
      {DVec3(-1.0, 0.0, g), 0.0},   // x <= G w
      {DVec3(1.0, 0.0, g), 0.0},    // x >= -G w
      {DVec3(0.0, -1.0, g), 0.0},   // y <= G w
      {DVec3(0.0, 1.0, g), 0.0},    // y >= -G w
  }};
  Vec4* src = a.data();
  Vec4* dst = b.data();
  for (const auto& [xyw, z] : planes) {
    n = clipPolygon(src, n, xyw, z, dst);
    if (n < 3) return;
    std::swap(src, dst);
  }
  std::array<RasterVertex, 9> r;
  for (int i = 0; i < n; ++i) {
    // On the guard-band planes w can only be 0 where x = y = 0 and the polygon is degenerate.
    if (!(src[i].w > 0.0f)) return;
    r[i] = toRaster(src[i], ctx);
  }
  for (int i = 1; i + 1 < n; ++i) setupTriangle(r[0], r[i], r[i + 1], triangle, ctx, out);
}

void buildChunk(const RasterInput& input, const ScratchVector<uint8_t>& codes, const ScratchVector<RasterVertex>& rv,
                size_t begin, size_t end, const Context& ctx, Chunk& chunk) {
  chunk.setups.reserve(end - begin);
  for (size_t i = begin; i < end; ++i) {
    const glm::uvec3& t = input.triangles[i];
    const uint8_t c0 = codes[t.x], c1 = codes[t.y], c2 = codes[t.z];
    if ((c0 | c1 | c2) & kNonFinite) continue;
    if (c0 & c1 & c2 & kRejectMask) continue;  // wholly outside one viewport plane
    const auto index = static_cast<int32_t>(i);
    if (((c0 | c1 | c2) & kNeedsClip) == 0)
      setupTriangle(rv[t.x], rv[t.y], rv[t.z], index, ctx, chunk.setups);
    else
      clipAndSetup(input.clipPositions[t.x], input.clipPositions[t.y], input.clipPositions[t.z], index, ctx,
                   chunk.setups);
  }
  // Counting sort of (tile, setup) pairs by tile; setups stay in input order within a tile.
  const size_t tileCount = static_cast<size_t>(ctx.tilesX) * ctx.tilesY;
  chunk.tileStart.assign(tileCount + 1, 0);
  auto forEachTile = [&](const Setup& s, auto&& f) {
    for (int ty = s.yMin / kTileSize; ty <= s.yMax / kTileSize; ++ty)
      for (int tx = s.xMin / kTileSize; tx <= s.xMax / kTileSize; ++tx) f(static_cast<size_t>(ty) * ctx.tilesX + tx);
  };
  for (const Setup& s : chunk.setups) forEachTile(s, [&](size_t tile) { ++chunk.tileStart[tile + 1]; });
  for (size_t t = 0; t < tileCount; ++t) chunk.tileStart[t + 1] += chunk.tileStart[t];
  chunk.items.resize(chunk.tileStart[tileCount]);
  ScratchVector<uint32_t> cursor(chunk.tileStart.begin(), chunk.tileStart.end() - 1);
  for (uint32_t k = 0; k < chunk.setups.size(); ++k)
    forEachTile(chunk.setups[k], [&](size_t tile) { chunk.items[cursor[tile]++] = k; });
}

struct TileBuffers {
  std::array<float, kTileSize * kTileSize> key;
  std::array<int32_t, kTileSize * kTileSize> winner;
  std::array<float, kTileSize * kTileSize> farKey;  //!< kFarthest only: the largest key and its triangle
  std::array<int32_t, kTileSize * kTileSize> farWinner;
};

// Rasterizes one setup into the tile whose top-left pixel is (tx0, ty0); with kFarthest, the
// deepest covering triangle too.
template <bool kFarthest>
void rasterizeInTile(const Setup& s, int tx0, int ty0, const Context& ctx, TileBuffers& tile) {
  const int x0 = std::max(s.xMin, tx0), x1 = std::min({s.xMax, tx0 + kTileSize - 1});
  const int y0 = std::max(s.yMin, ty0), y1 = std::min({s.yMax, ty0 + kTileSize - 1});
  if (x0 > x1 || y0 > y1) return;
  constexpr int64_t S = kSubpixelScale;
  // Edge k runs from vertex k to vertex k+1; E(P) = dx (P.y - A.y) - dy (P.x - A.x) >= 0 inside.
  // Top-left rule: a sample with E == 0 is inside only on a top edge (dy == 0, dx > 0) or a left
  // edge (dy < 0); elsewhere the bias -1 turns E == 0 into "outside" (E is an integer).
  std::array<int64_t, 3> row, stepX, stepY;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3;
    const int64_t dx = static_cast<int64_t>(s.x[k1]) - s.x[k];
    const int64_t dy = static_cast<int64_t>(s.y[k1]) - s.y[k];
    const bool topLeft = dy < 0 || (dy == 0 && dx > 0);
    const int64_t px = x0 * S + S / 2 - s.x[k], py = y0 * S + S / 2 - s.y[k];
    row[k] = dx * py - dy * px + (topLeft ? 0 : -1);
    stepX[k] = -dy * S;
    stepY[k] = dx * S;
  }
  const double vx = static_cast<double>(s.x[0]) / S, vy = static_cast<double>(s.y[0]) / S;
  const int n = x1 - x0 + 1;
  const float keyDx = s.keyDx;
  const int32_t id = s.triangle;
  for (int y = y0; y <= y1; ++y) {
    const float keyRow =
        static_cast<float>(s.key0 + s.keyDx * (x0 + 0.5 - vx) + static_cast<double>(s.keyDy) * (y + 0.5 - vy));
    float* key = tile.key.data() + (y - ty0) * kTileSize + (x0 - tx0);
    int32_t* winner = tile.winner.data() + (y - ty0) * kTileSize + (x0 - tx0);
    float* farKey = tile.farKey.data() + (y - ty0) * kTileSize + (x0 - tx0);
    int32_t* farWinner = tile.farWinner.data() + (y - ty0) * kTileSize + (x0 - tx0);
    int64_t e0 = row[0], e1 = row[1], e2 = row[2];
    const int64_t s0 = stepX[0], s1 = stepX[1], s2 = stepX[2];
    // Branch-free over the row: coverage (all three edge functions >= 0, i.e. their OR has no sign
    // bit), depth test, select.
    for (int i = 0; i < n; ++i) {
      const float k = keyRow + keyDx * static_cast<float>(i);
      const bool covered = (e0 | e1 | e2) >= 0;
      const bool pass = covered & (k < key[i]);
      key[i] = pass ? k : key[i];
      winner[i] = pass ? id : winner[i];
      if constexpr (kFarthest) {
        const bool deeper = covered & (k > farKey[i]);
        farKey[i] = deeper ? k : farKey[i];
        farWinner[i] = deeper ? id : farWinner[i];
      }
      e0 += s0;
      e1 += s1;
      e2 += s2;
    }
    row[0] += stepY[0];
    row[1] += stepY[1];
    row[2] += stepY[2];
  }
}

// Perspective-correct barycentrics of the pixel centre (ndcX, ndcY) in the clip-space triangle
// (c0, c1, c2): the solution u of sum u_i (x_i, y_i, w_i) = (ndcX, ndcY, 1), normalized (Olano &
// Greer 1997). u = adj(M) p / det(M) with M's columns c_i; the rows of adj(M) are cross products.
// The rows depend on the triangle alone, so they are set up once per run of pixels that share a
// winning triangle (most of a large triangle's row) and each pixel pays three dot products; the
// arithmetic per pixel is the same as computing the rows afresh, so the result is bit-identical.
struct HomogeneousTriangle {
  glm::dvec3 row0{0.0}, row1{0.0}, row2{0.0};  // rows of adj(M)
  Vec3 w{0.0f};                                // clip w of the three vertices
  explicit HomogeneousTriangle(const Vec4& c0, const Vec4& c1, const Vec4& c2) : w(c0.w, c1.w, c2.w) {
    const glm::dvec3 m0(c0.x, c0.y, c0.w), m1(c1.x, c1.y, c1.w), m2(c2.x, c2.y, c2.w);
    row0 = glm::cross(m1, m2);
    row1 = glm::cross(m2, m0);
    row2 = glm::cross(m0, m1);
  }
  HomogeneousTriangle() = default;

  glm::dvec3 barycentrics(double ndcX, double ndcY) const {
    const glm::dvec3 p(ndcX, ndcY, 1.0);
    glm::dvec3 u(glm::dot(row0, p), glm::dot(row1, p), glm::dot(row2, p));
    u *= 1.0 / (u.x + u.y + u.z);
    // Snapping may put a covered pixel centre up to 1/512 pixel outside the exact triangle: clamp to
    // it. A triangle whose plane passes through the eye has no solution (it covers no area in exact
    // arithmetic); its centroid stands in.
    if (!std::isfinite(u.x) || !std::isfinite(u.y) || !std::isfinite(u.z)) return glm::dvec3(1.0 / 3.0);
    if (u.x < 0.0 || u.y < 0.0 || u.z < 0.0) {
      u = glm::max(u, glm::dvec3(0.0));
      u *= 1.0 / (u.x + u.y + u.z);
    }
    return u;
  }
};

void validate(const RasterInput& input) {
  if (input.width < 1 || input.height < 1 || input.width > kMaxImageSize || input.height > kMaxImageSize)
    fail("rasterizer: image size must be within 1..{} pixels per side (got {} x {})", kMaxImageSize, input.width,
         input.height);
  if (input.attributeCount < 0) fail("rasterizer: attribute count must be >= 0 (got {})", input.attributeCount);
  const size_t vertexCount = input.clipPositions.size();
  if (vertexCount > static_cast<size_t>(INT32_MAX) || input.triangles.size() > static_cast<size_t>(INT32_MAX))
    fail("rasterizer: at most {} vertices and triangles per call (got {} and {})", INT32_MAX, vertexCount,
         input.triangles.size());
  if (input.attributes.size() != vertexCount * static_cast<size_t>(input.attributeCount))
    fail("rasterizer: expected {} attribute floats ({} vertices x {} channels), got {}",
         vertexCount * input.attributeCount, vertexCount, input.attributeCount, input.attributes.size());
  if (input.farthestLayer && !input.farthestTiles.empty()) {
    const size_t tiles = static_cast<size_t>((input.width + kTileSize - 1) / kTileSize) *
                         static_cast<size_t>((input.height + kTileSize - 1) / kTileSize);
    if (input.farthestTiles.size() != tiles)
      fail("rasterizer: expected one far-layer flag per {}-pixel tile ({}), got {}", kTileSize, tiles,
           input.farthestTiles.size());
  }
  if (!input.payloads.empty() && input.payloads.size() != input.triangles.size())
    fail("rasterizer: expected one payload per triangle ({}), got {}", input.triangles.size(), input.payloads.size());
  for (size_t i = 0; i < input.triangles.size(); ++i) {
    const glm::uvec3& t = input.triangles[i];
    if (t.x >= vertexCount || t.y >= vertexCount || t.z >= vertexCount)
      fail("rasterizer: triangle {} references vertex {}, but there are only {} vertices", i, std::max({t.x, t.y, t.z}),
           vertexCount);
  }
}

}  // namespace

void rasterize(const RasterInput& input, const TileVisitor& visit) {
  validate(input);
  Context ctx;
  ctx.width = input.width;
  ctx.height = input.height;
  ctx.tilesX = (input.width + kTileSize - 1) / kTileSize;
  ctx.tilesY = (input.height + kTileSize - 1) / kTileSize;
  ctx.guardBand = guardBandFor(input.width, input.height);

  // 1. Vertices.
  const size_t vertexCount = input.clipPositions.size();
  ScratchVector<uint8_t> codes(vertexCount);
  ScratchVector<RasterVertex> rv(vertexCount);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, vertexCount, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      codes[i] = outcode(input.clipPositions[i], ctx.guardBand);
      rv[i] = (codes[i] & (kNeedsClip | kNonFinite)) ? RasterVertex{0, 0, 0.0f} : toRaster(input.clipPositions[i], ctx);
    }
  });

  // 2. Triangle setup and binning, in fixed chunks.
  const size_t triangleCount = input.triangles.size();
  const size_t chunkCount = (triangleCount + kChunkTriangles - 1) / kChunkTriangles;
  ScratchVector<Chunk> chunks(chunkCount);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, chunkCount, 1), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c < r.end(); ++c)
      buildChunk(input, codes, rv, c * kChunkTriangles, std::min(triangleCount, (c + 1) * kChunkTriangles), ctx,
                 chunks[c]);
  });

  // 3. Tiles: visibility, then one resolve per covered pixel against its winning original triangle.
  const int W = input.width, H = input.height;
  tbb::parallel_for(tbb::blocked_range<int>(0, ctx.tilesX * ctx.tilesY, 1), [&](const tbb::blocked_range<int>& r) {
    TileBuffers tile;
    std::array<Vec3, kTileSize * kTileSize> barycentrics, farBarycentrics;
    std::array<float, kTileSize * kTileSize> clipW;
    for (int t = r.begin(); t < r.end(); ++t) {
      const bool farthest =
          input.farthestLayer && (input.farthestTiles.empty() || input.farthestTiles[static_cast<size_t>(t)] != 0);
      const int tx0 = (t % ctx.tilesX) * kTileSize, ty0 = (t / ctx.tilesX) * kTileSize;
      tile.key.fill(kInfinity);
      tile.winner.fill(-1);
      if (farthest) {
        tile.farKey.fill(-kInfinity);
        tile.farWinner.fill(-1);
      }
      for (const Chunk& chunk : chunks)
        for (uint32_t k = chunk.tileStart[t]; k < chunk.tileStart[t + 1]; ++k)
          if (farthest)
            rasterizeInTile<true>(chunk.setups[chunk.items[k]], tx0, ty0, ctx, tile);
          else
            rasterizeInTile<false>(chunk.setups[chunk.items[k]], tx0, ty0, ctx, tile);
      TileSamples samples;
      samples.x0 = tx0;
      samples.y0 = ty0;
      samples.width = std::min(kTileSize, W - tx0);
      samples.height = std::min(kTileSize, H - ty0);
      const double ndcPerPixelX = 2.0 / W, ndcPerPixelY = 2.0 / H;
      int32_t cachedTriangle = -1;
      HomogeneousTriangle h;
      for (int j = 0; j < samples.height; ++j) {
        const double ndcY = 1.0 - (ty0 + j + 0.5) * ndcPerPixelY;
        for (int i = 0; i < samples.width; ++i) {
          const int32_t tri = tile.winner[j * kTileSize + i];
          if (tri < 0) continue;
          if (tri != cachedTriangle) {
            const glm::uvec3& v = input.triangles[static_cast<size_t>(tri)];
            h = HomogeneousTriangle(input.clipPositions[v.x], input.clipPositions[v.y], input.clipPositions[v.z]);
            cachedTriangle = tri;
          }
          const double ndcX = (tx0 + i + 0.5) * ndcPerPixelX - 1.0;
          const glm::dvec3 b = h.barycentrics(ndcX, ndcY);
          barycentrics[j * kTileSize + i] = Vec3(b);
          clipW[j * kTileSize + i] = static_cast<float>(b.x * h.w.x + b.y * h.w.y + b.z * h.w.z);
        }
      }
      if (farthest) {
        cachedTriangle = -1;
        for (int j = 0; j < samples.height; ++j) {
          const double ndcY = 1.0 - (ty0 + j + 0.5) * ndcPerPixelY;
          for (int i = 0; i < samples.width; ++i) {
            const int32_t tri = tile.farWinner[j * kTileSize + i];
            if (tri < 0) continue;
            // One surface under the pixel (the near layer's triangle is also the deepest): the same
            // solve as the near layer's, already made.
            if (tri == tile.winner[j * kTileSize + i]) {
              farBarycentrics[j * kTileSize + i] = barycentrics[j * kTileSize + i];
              continue;
            }
            if (tri != cachedTriangle) {
              const glm::uvec3& v = input.triangles[static_cast<size_t>(tri)];
              h = HomogeneousTriangle(input.clipPositions[v.x], input.clipPositions[v.y], input.clipPositions[v.z]);
              cachedTriangle = tri;
            }
            farBarycentrics[j * kTileSize + i] = Vec3(h.barycentrics((tx0 + i + 0.5) * ndcPerPixelX - 1.0, ndcY));
          }
        }
        samples.farTriangle = tile.farWinner.data();
        samples.farBarycentrics = farBarycentrics.data();
      }
      samples.triangle = tile.winner.data();
      samples.depth = tile.key.data();
      samples.barycentrics = barycentrics.data();
      samples.clipW = clipW.data();
      visit(samples);
    }
  });
}

RasterOutput rasterize(const RasterInput& input) {
  validate(input);
  RasterOutput out;
  const int W = input.width, H = input.height, N = input.attributeCount;
  out.depth = Image<float>(W, H, kInfinity);
  out.clipW = Image<float>(W, H, kInfinity);
  out.triangle = Image<int32_t>(W, H, -1);
  out.payload = Image<int32_t>(W, H, -1);
  out.attributes.assign(static_cast<size_t>(N), Image<float>(W, H, 0.0f));
  rasterize(input, [&](const TileSamples& s) {
    for (int j = 0; j < s.height; ++j)
      for (int i = 0; i < s.width; ++i) {
        const int k = j * kTileSize + i;
        const int32_t tri = s.triangle[k];
        if (tri < 0) continue;
        const int x = s.x0 + i, y = s.y0 + j;
        out.depth(x, y) = s.depth[k];
        out.clipW(x, y) = s.clipW[k];
        out.triangle(x, y) = tri;
        out.payload(x, y) = input.payloads.empty() ? -1 : input.payloads[static_cast<size_t>(tri)];
        if (N == 0) continue;
        const glm::uvec3& v = input.triangles[static_cast<size_t>(tri)];
        const Vec3& b = s.barycentrics[k];
        const float* a0 = input.attributes.data() + static_cast<size_t>(v.x) * N;
        const float* a1 = input.attributes.data() + static_cast<size_t>(v.y) * N;
        const float* a2 = input.attributes.data() + static_cast<size_t>(v.z) * N;
        for (int ch = 0; ch < N; ++ch) out.attributes[ch](x, y) = b.x * a0[ch] + b.y * a1[ch] + b.z * a2[ch];
      }
  });
  return out;
}

}  // namespace penumbra::raster
