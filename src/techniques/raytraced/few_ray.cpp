// The shared stages of few_ray.h.
#include "few_ray.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "core/target_clones.h"
#include "rt/shadow_packet.h"

namespace penumbra::raytraced {
namespace {

// A float in [0, 1) from the top 24 bits of a hash.
inline float unitFloat(uint32_t h) { return static_cast<float>(h >> 8) * 0x1p-24f; }

// u + offset modulo 1, kept below 1 where the sum rounds up to it. A select the compiler vectorizes
// (few_ray.cpp is built without trapping math, CMakeLists.txt): as a branch, the random offsets
// mispredicted it about every other lane.
inline float rotate(float u, float offset) {
  constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;
  const float r = u + offset;
  return std::min(r >= 1.0f ? r - 1.0f : r, kOneMinusEpsilon);
}

// Each pixel's Cranley-Patterson offset (few_ray.h) from the hash of (seed, pixel index), for
// `count` pixels in one loop, compiled for AVX2 and AVX-512F too (core/target_clones.h): the 64-bit
// multiplies of the hashes are what the loop spends, and every target gives the same bits.
PENUMBRA_CLONES_AVX512 void pixelOffsets(uint64_t seed, int count, const uint64_t* __restrict pixel,
                                         float* __restrict offsetX, float* __restrict offsetY) {
  for (int i = 0; i < count; ++i) {
    offsetX[i] = unitFloat(hashCombine(seed, 2 * pixel[i]));
    offsetY[i] = unitFloat(hashCombine(seed, 2 * pixel[i] + 1));
  }
}

}  // namespace

void FewRayFrame::reset(int w, int h) {
  width = w;
  height = h;
  tilesX = (w + kTile - 1) / kTile;
  tilesY = (h + kTile - 1) / kTile;
  // Not cleared: every pixel that sees geometry is written before it is read (a uniform tile's
  // stand-ins, a penumbra tile's clearTile and rays, hybrid's classes), and the rest are never read.
  // Clearing 16 bytes a pixel every frame cost a pass over the whole image.
  sums.resize(static_cast<size_t>(w) * h);
  tiles.assign(static_cast<size_t>(tilesX) * tilesY, TileClass::Empty);
  penumbra.assign(tiles.size(), 0);
}

void FewRayFrame::reserve(int w, int h) {
  reset(w, h);  // sums, as std::vector makes them: zeroed
  for (Image<float>* image : {&noisy, &radius, &reach, &scratch}) resetInParallel(*image, w, h, 0.0f);
}

TileRayTracer::TileRayTracer(const RayScene& scene, const Light& light, float epsilon, int samplesPerPixel,
                             uint64_t seed)
    : scene_(scene), light_(light), epsilon_(epsilon), seed_(seed) {
  const CmjSampler cmj(static_cast<uint32_t>(std::max(samplesPerPixel, 1)));
  const uint32_t pattern = hashCombine(seed, 0x5eedull);
  for (uint32_t i = 0; i < cmj.count(); ++i) points_.push_back(cmj.sample(i, pattern));
}

int64_t TileRayTracer::traceTile(const GBuffer& gbuffer, int tile, uint32_t first, uint32_t last,
                                 FewRayFrame& frame) const {
  const TileBounds b = frame.bounds(tile);
  int64_t rays = 0;
  // One packet per sample index over the (up to) 16 pixels of an 8 x 2 block: neighbouring origins
  // aiming at one light form a narrow bundle, and at low spp a packet of one pixel's samples would
  // leave most of its 16 lanes idle.
  for (int y0Block = b.y0; y0Block < b.y1; y0Block += 2) {
    int xs[16], ys[16], count = 0;
    for (int y = y0Block; y < std::min(y0Block + 2, b.y1); ++y)
      for (int x = b.x0; x < b.x1; ++x)
        if (gbuffer.hit(x, y)) {
          xs[count] = x;
          ys[count++] = y;
        }
    rays += tracePixels(gbuffer, xs, ys, count, first, last, frame);
  }
  return rays;
}

int64_t TileRayTracer::probeTile(const GBuffer& gbuffer, int tile, FewRayFrame& frame) const {
  const auto [x0, y0, x1, y1] = frame.bounds(tile);
  // One pixel of each 2 x 2 quad that sees geometry, the first in an order that starts at a hashed
  // corner (a fixed corner would probe a regular lattice, which aliases with regular geometry).
  int xs[16], ys[16], count = 0;
  for (int qy = y0; qy < y1; qy += 2)
    for (int qx = x0; qx < x1; qx += 2) {
      const uint32_t start = hashCombine(seed_, static_cast<uint64_t>(qy) * frame.width + qx) & 3u;
      for (uint32_t k = 0; k < 4; ++k) {
        const uint32_t corner = (start + k) & 3u;
        const int x = qx + static_cast<int>(corner & 1u), y = qy + static_cast<int>(corner >> 1);
        if (x < x1 && y < y1 && gbuffer.hit(x, y)) {
          xs[count] = x;
          ys[count++] = y;
          break;
        }
      }
    }
  for (int i = 0; i < count; ++i) frame.at(xs[i], ys[i]) = RaySums{};  // the rays add to the sums
  const int64_t rays = tracePixels(gbuffer, xs, ys, count, 0, 1, frame);
  int blocked = 0;
  float ratio = 0.0f;
  for (int i = 0; i < count; ++i) {
    const RaySums& p = frame.at(xs[i], ys[i]);
    blocked += p.blocked;
    ratio += p.ratio;
  }
  const TileClass c = count == 0         ? TileClass::Empty
                      : blocked == 0     ? TileClass::Lit
                      : blocked == count ? TileClass::Umbra
                                         : TileClass::Mixed;
  frame.tiles[static_cast<size_t>(tile)] = c;
  // A uniform tile's pixels all take its probes' answer (and, in umbra, their mean width ratio); a
  // mixed tile is a penumbra tile, whose pixels are traced again in full.
  if (c == TileClass::Lit || c == TileClass::Umbra) {
    const RaySums standIn =
        c == TileClass::Lit ? RaySums{1.0f, 1.0f, 0.0f, 0} : RaySums{1.0f, 0.0f, ratio / static_cast<float>(count), 1};
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        if (gbuffer.hit(x, y)) frame.at(x, y) = standIn;
  }
  return rays;
}

void FewRayFrame::clearTile(int tile) {
  const TileBounds b = bounds(tile);
  for (int y = b.y0; y < b.y1; ++y)
    for (int x = b.x0; x < b.x1; ++x) at(x, y) = RaySums{};
}

int64_t TileRayTracer::tracePixels(const GBuffer& gbuffer, const int* xs, const int* ys, int count, uint32_t first,
                                   uint32_t last, FewRayFrame& frame) const {
  if (count == 0) return 0;
  rt::ShadowLanes lanes;
  alignas(64) float offsetX[16], offsetY[16];
  // The lanes' sums through one raw pointer and their indices: through frame.at, each byte stored to
  // a sum's `blocked` (a char type, which may alias anything) made the compiler reload the frame's
  // storage and width.
  RaySums* const sums = frame.sums.data();
  alignas(64) uint64_t sumIndex[16];
  for (int i = 0; i < count; ++i) {
    const int x = xs[i], y = ys[i];
    lanes.setSurface(i, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y));
    sumIndex[i] = static_cast<uint64_t>(y) * frame.width + x;
  }
  pixelOffsets(seed_, count, sumIndex, offsetX, offsetY);
  rt::offsetOrigins(light_, epsilon_, count, lanes);
  const bool directional = light_.isDirectional();
  RayHitPacket16 packet;
  alignas(64) float weights[16], tLight[16];
  for (uint32_t index = first; index < last; ++index) {
    const Vec2 point = points_[index];
    for (int i = 0; i < count; ++i) {
      lanes.ux[i] = rotate(point.x, offsetX[i]);
      lanes.uy[i] = rotate(point.y, offsetY[i]);
    }
    rt::buildShadowRays(light_, lanes, count, epsilon_, packet.ray, weights);
    std::copy(packet.ray.tMax, packet.ray.tMax + count, tLight);  // the hit overwrites tMax
    scene_.intersect16(packet, count);
    for (int i = 0; i < count; ++i) {
      RaySums& p = sums[sumIndex[i]];
      p.weight += weights[i];
      if (packet.hit.geomId[i] == HitPacket16::kNoHit) {
        p.visible += weights[i];
        continue;
      }
      // The blocker's distance over what is left to the light point; a directional light's is
      // infinite, so its ratio is the distance itself.
      const float t = packet.ray.tMax[i];
      p.ratio += directional ? t : t / std::max(tLight[i] - t, 1e-6f * tLight[i]);
      ++p.blocked;
    }
  }
  return static_cast<int64_t>(count) * (last - first);
}

TileClass classifyTile(const GBuffer& gbuffer, const FewRayFrame& frame, int tile) {
  const TileBounds b = frame.bounds(tile);
  int hits = 0, lit = 0, umbra = 0;
  for (int y = b.y0; y < b.y1; ++y)
    for (int x = b.x0; x < b.x1; ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const RaySums& p = frame.at(x, y);
      ++hits;
      lit += p.blocked == 0;
      umbra += p.visible == 0.0f;
    }
  return hits == 0       ? TileClass::Empty
         : lit == hits   ? TileClass::Lit
         : umbra == hits ? TileClass::Umbra
                         : TileClass::Mixed;
}

int markPenumbraTiles(FewRayFrame& frame, bool skipUniform) {
  int marked = 0;
  for (int ty = 0; ty < frame.tilesY; ++ty)
    for (int tx = 0; tx < frame.tilesX; ++tx) {
      const TileClass c = frame.tiles[static_cast<size_t>(ty) * frame.tilesX + tx];
      if (c == TileClass::Empty) continue;
      bool mark = !skipUniform || c == TileClass::Mixed;
      for (int ny = std::max(0, ty - 1); ny <= std::min(frame.tilesY - 1, ty + 1) && !mark; ++ny)
        for (int nx = std::max(0, tx - 1); nx <= std::min(frame.tilesX - 1, tx + 1) && !mark; ++nx) {
          const TileClass n = frame.tiles[static_cast<size_t>(ny) * frame.tilesX + nx];
          mark = n == TileClass::Mixed || (n != TileClass::Empty && n != c);
        }
      frame.penumbra[static_cast<size_t>(ty) * frame.tilesX + tx] = mark ? 1 : 0;
      marked += mark;
    }
  return marked;
}

int64_t tracePenumbraTiles(const GBuffer& gbuffer, const TileRayTracer& tracer, uint32_t spp, FewRayFrame& frame) {
  std::atomic<int64_t> rays{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, static_cast<int>(frame.tiles.size())),
                    [&](const tbb::blocked_range<int>& range) {
                      int64_t local = 0;
                      for (int tile = range.begin(); tile < range.end(); ++tile)
                        if (frame.penumbra[static_cast<size_t>(tile)]) {
                          frame.clearTile(tile);
                          local += tracer.traceTile(gbuffer, tile, 0, spp, frame);
                        }
                      rays += local;
                    });
  return rays.load();
}

void resolveVisibility(const GBuffer& gbuffer, FewRayFrame& frame, const Light& light, int samplesPerPixel,
                       const PenumbraFilterOptions& filter, float tanHalfFovY, const Image<float>* fallbackRatio,
                       Image<float>& v) {
  const int width = frame.width, height = frame.height;
  const int tiles = static_cast<int>(frame.tiles.size());
  auto forTiles = [&](auto&& f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles), [&](const tbb::blocked_range<int>& range) {
      for (int tile = range.begin(); tile < range.end(); ++tile) f(tile, frame.bounds(tile));
    });
  };
  // Each tile's sums of the width ratios of its blocked rays, for its neighbours' pixels that have none.
  std::vector<float> tileRatio(frame.tiles.size(), 0.0f);
  std::vector<int> tileBlocked(frame.tiles.size(), 0);
  forTiles([&](int tile, const TileBounds& b) {
    float ratio = 0.0f;
    int blocked = 0;
    for (int y = b.y0; y < b.y1; ++y)
      for (int x = b.x0; x < b.x1; ++x)
        if (gbuffer.hit(x, y)) {
          ratio += frame.at(x, y).ratio;
          blocked += frame.at(x, y).blocked;
        }
    tileRatio[static_cast<size_t>(tile)] = ratio;
    tileBlocked[static_cast<size_t>(tile)] = blocked;
  });
  const float lightDiameter = 2.0f * light.extent();
  // min_radius is for the noise of 2 rays a pixel; the noise falls as 1 / sqrt(spp), and so does the floor.
  const float minRadius = filter.minRadius * std::sqrt(2.0f / static_cast<float>(std::max(samplesPerPixel, 1)));
  Image<float>& noisy = frame.noisy;
  Image<float>& radius = frame.radius;
  Image<float>& reach = frame.reach;
  resetInParallel(noisy, width, height, 1.0f);
  resetInParallel(radius, width, height, 0.0f);
  resetInParallel(reach, width, height, kInfinity);
  forTiles([&](int tile, const TileBounds& b) {
    const int tx = tile % frame.tilesX, ty = tile / frame.tilesX;
    const bool penumbra = frame.penumbra[static_cast<size_t>(tile)] != 0;
    // The width ratio of a penumbra pixel none of whose rays was blocked, when the caller has none:
    // the mean over the 3 x 3 tiles around.
    float neighbourhood = 0.0f;
    if (penumbra) {
      float sum = 0.0f;
      int count = 0;
      for (int ny = std::max(0, ty - 1); ny <= std::min(frame.tilesY - 1, ty + 1); ++ny)
        for (int nx = std::max(0, tx - 1); nx <= std::min(frame.tilesX - 1, tx + 1); ++nx) {
          sum += tileRatio[static_cast<size_t>(ny) * frame.tilesX + nx];
          count += tileBlocked[static_cast<size_t>(ny) * frame.tilesX + nx];
        }
      neighbourhood = count > 0 ? sum / static_cast<float>(count) : 0.0f;
    }
    for (int y = b.y0; y < b.y1; ++y)
      for (int x = b.x0; x < b.x1; ++x) {
        if (!gbuffer.hit(x, y)) continue;
        const RaySums& p = frame.at(x, y);
        noisy(x, y) = p.weight > 0.0f ? p.visible / p.weight : 1.0f;
        const bool umbra = p.blocked > 0 && p.visible == 0.0f;
        if (!umbra && !penumbra) continue;
        const float footprint = pixelFootprint(gbuffer.csDepth(x, y), tanHalfFovY, height);
        auto toRadius = [&](float ratio) {
          return std::min(filter.maxRadius, filter.filterScale * lightDiameter * ratio / footprint);
        };
        // A pixel all of whose rays were blocked reaches only as far as its own radius (penumbra_filter.h).
        if (umbra) reach(x, y) = toRadius(p.ratio / p.blocked);
        if (!penumbra) continue;
        const float ratio = p.blocked > 0                                    ? p.ratio / p.blocked
                            : fallbackRatio && (*fallbackRatio)(x, y) > 0.0f ? (*fallbackRatio)(x, y)
                                                                             : neighbourhood;
        // A penumbra pixel with a lit ray filters over at least min_radius: a penumbra a pixel or two
        // wide would otherwise keep its few rays' 0s and 1s as specks. One all of whose rays were
        // blocked keeps its own radius: raised, it would average lit neighbours into a sharp umbra.
        radius(x, y) = umbra ? toRadius(ratio) : std::max(minRadius, toRadius(ratio));
      }
  });
  if (!(filter.filterScale > 0.0f)) {
    resetInParallel(v, width, height, 1.0f);
    std::copy(noisy.begin(), noisy.end(), v.begin());
    return;
  }
  PenumbraFilterInput input;
  input.noisy = &noisy;
  input.radius = &radius;
  input.reach = &reach;
  input.tanHalfFovY = tanHalfFovY;
  input.activeTiles = frame.penumbra.data();
  input.tileSize = kTile;
  input.tilesX = frame.tilesX;
  filterPenumbrae(gbuffer, input, filter, frame.scratch, v);
}

void TemporalHistory::accumulate(const GBuffer& gbuffer, const Camera& camera, const TemporalOptions& options,
                                 Image<float>& v) {
  const int width = gbuffer.width(), height = gbuffer.height();
  const bool hasHistory = frames_ > 0 && v_.width() == width && v_.height() == height;
  if (hasHistory) {
    const Mat4 rasterFromWs = camera_.rasterFromWs(width, height);  // the previous frame's camera
    const float tanHalfNow = std::tan(0.5f * radians(camera.fovYDegrees));
    resetInParallel(blended_, width, height, 1.0f);
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < width; ++x) {
          blended_(x, y) = v(x, y);
          if (!gbuffer.hit(x, y)) continue;
          const Vec3 p = gbuffer.wsPosition(x, y);
          const Vec4 q = rasterFromWs * Vec4(p, 1.0f);
          if (!(q.w > 0.0f)) continue;
          const float px = q.x / q.w, py = q.y / q.w;
          if (!(px >= 0.0f && py >= 0.0f && px < static_cast<float>(width) && py < static_cast<float>(height)))
            continue;
          const int hx = static_cast<int>(px), hy = static_cast<int>(py);
          const int32_t id = gbuffer.objectId(x, y);
          if (objectIds_(hx, hy) != id) continue;
          const float footprint = pixelFootprint(gbuffer.csDepth(x, y), tanHalfNow, height);
          if (!(glm::length(positions_(hx, hy) - p) <= 2.0f * footprint)) continue;
          float lo = v(x, y), hi = v(x, y);
          for (int ny = std::max(0, y - 1); ny <= std::min(height - 1, y + 1); ++ny)
            for (int nx = std::max(0, x - 1); nx <= std::min(width - 1, x + 1); ++nx)
              if (gbuffer.objectId(nx, ny) == id) {
                lo = std::min(lo, v(nx, ny));
                hi = std::max(hi, v(nx, ny));
              }
          const float h = std::clamp(v_(hx, hy), lo - options.clampMargin, hi + options.clampMargin);
          blended_(x, y) = h + options.alpha * (v(x, y) - h);
        }
    });
    std::swap(v, blended_);  // blended_ keeps the old storage for the next frame
  }
  v_ = v;
  positions_ = gbuffer.wsPosition;
  objectIds_ = gbuffer.objectId;
  camera_ = camera;
  ++frames_;
}

void FewRayState::prepare(const Scene& scene, const Light& aimedAt) {
  rays = nullptr;
  rays = &raysCache.get(scene);
  light = aimedAt;
  epsilon = shadowRayEpsilon(raysCache.bounds());
  tanHalfFovY = std::tan(0.5f * radians(scene.camera.fovYDegrees));
  camera = scene.camera;
}

uint64_t FewRayState::frameSeed(const TemporalOptions& temporal, uint64_t seed) const {
  return temporal.enabled ? hashCombine(seed, history.frames()) : seed;
}

std::vector<std::pair<std::string, double>> FewRayState::stats(const std::string& firstStage) const {
  return {{"rays", rayCount},
          {"penumbra_tile_fraction", penumbraTileFraction},
          {firstStage + "_ms", stageMs[0]},
          {"rays_ms", stageMs[1]},
          {"filter_ms", stageMs[2]}};
}

}  // namespace penumbra::raytraced
