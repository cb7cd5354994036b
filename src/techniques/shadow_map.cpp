// Shared shadow-map stages: see shadow_map.h for the papers, the conventions and the approximations.
#include "shadow_map.h"

#include <algorithm>
#include <cmath>

#include "penumbra/error.h"

namespace penumbra {

ParamSpec mapSizeParamSpec(int64_t defaultSize) {
  return ParamSpec{.name = "map_size",
                   .type = ParamType::Int,
                   .defaultValue = defaultSize,
                   .min = static_cast<double>(kMinShadowMapSize),
                   .max = static_cast<double>(kMaxShadowMapSize), .choices = {},
                   .unit = "texels",
                   .help = "width and height of the square light-space depth map"};
}

ParamSpec biasConstantParamSpec() {
  return ParamSpec{.name = "bias_constant",
                   .type = ParamType::Float,
                   .defaultValue = double{DepthBias{}.constantTexels},
                   .min = 0.0,
                   .max = 64.0, .choices = {},
                   .unit = "texels",
                   .help = "constant depth bias, in world sizes of one texel at the receiver's depth"};
}

ParamSpec biasSlopeParamSpec() {
  return ParamSpec{.name = "bias_slope",
                   .type = ParamType::Float,
                   .defaultValue = double{DepthBias{}.slope},
                   .min = 0.0,
                   .max = 64.0, .choices = {},
                   .unit = "",
                   .help = "slope-scaled depth bias: multiplies the receiver's depth change per texel"};
}

DepthBias depthBiasFromParams(const Params& params) {
  DepthBias bias;
  bias.constantTexels = static_cast<float>(params.getFloat("bias_constant"));
  bias.slope = static_cast<float>(params.getFloat("bias_slope"));
  return bias;
}

LightMap createShadowMap(const Scene& scene, const Light& light, int mapSize) {
  if (mapSize < kMinShadowMapSize || mapSize > kMaxShadowMapSize)
    fail("shadow map: map_size = {} is not valid: expected an int in [{}, {}] texels", mapSize, kMinShadowMapSize,
         kMaxShadowMapSize);
  return renderLightMap(scene, light, mapSize);
}

float minMapDepth(const LightMap& map) {
  float m = kInfinity;
  const float* d = map.lsDepth.data();
  const size_t n = map.lsDepth.size();
  for (size_t i = 0; i < n; ++i) m = d[i] < m ? d[i] : m;
  return m;
}

namespace {

// num / den limited to [-kMaxDepthSlope, kMaxDepthSlope], also when den is 0.
float limitedRatio(float num, float den) {
  if (std::abs(num) <= kMaxDepthSlope * std::abs(den)) return num / den;
  const float sign = (num < 0.0f) != (den < 0.0f) ? -1.0f : 1.0f;
  return sign * kMaxDepthSlope;
}

}  // namespace

ShadowReceiver makeReceiver(const LightMap& map, const Vec3& wsPosition, const Vec3& wsGeometricNormal,
                            const DepthBias& bias) {
  ShadowReceiver r;
  const Vec3 lsP = map.lightFromRender(wsPosition);
  if (!map.orthographic && !(lsP.z > 0.0f)) return r;  // behind a local light: not in its map
  const Vec3 stz = map.project(wsPosition);
  r.s = stz.x;
  r.t = stz.y;
  r.lsDepth = stz.z;
  const float size = static_cast<float>(map.size);
  if (!(r.s >= 0.0f && r.s < size && r.t >= 0.0f && r.t < size) || !std::isfinite(r.lsDepth)) return r;
  r.inMap = true;
  r.texelWorld = map.texelWorldSize(r.lsDepth);
  // The receiver plane N.X = N.P met by the ray through map position (s, t). Perspective: the ray
  // is X = z (a, b, 1), a growing with s and b falling with t by texelWorld / z per texel, so
  // dz/ds = -Nx texelWorld / (N.d) and dz/dt = +Ny texelWorld / (N.d) with N.d = N.P / z.
  // Orthographic: X = (x, y, z), the same with N.d = Nz. Both in texel sizes per texel here.
  const Vec3 lsN = map.lsFrame.toLocal(wsGeometricNormal);
  const float nDotD = map.orthographic ? lsN.z : glm::dot(lsN, lsP) / lsP.z;
  const float gs = limitedRatio(-lsN.x, nDotD);
  const float gt = limitedRatio(lsN.y, nDotD);
  r.dzds = gs * r.texelWorld;
  r.dzdt = gt * r.texelWorld;
  r.bias = r.texelWorld * (bias.constantTexels + bias.slope * std::sqrt(gs * gs + gt * gt));
  return r;
}

float pcfBox(const LightMap& map, const ShadowReceiver& r, float s, float t, float widthTexels) {
  const float half = 0.5f * widthTexels;
  const float s0 = s - half, s1 = s + half, t0 = t - half, t1 = t + half;
  const int i0 = static_cast<int>(std::floor(s0)), i1 = static_cast<int>(std::floor(s1));
  const int j0 = static_cast<int>(std::floor(t0)), j1 = static_cast<int>(std::floor(t1));
  float sum = 0.0f;
  for (int j = j0; j <= j1; ++j) {
    const float fj = static_cast<float>(j);
    const float wt = std::min(t1, fj + 1.0f) - std::max(t0, fj);
    float row = 0.0f;
    for (int i = i0; i <= i1; ++i) {
      const float fi = static_cast<float>(i);
      const float ws = std::min(s1, fi + 1.0f) - std::max(s0, fi);
      row += ws * litAtTexel(map, r, i, j);
    }
    sum += wt * row;
  }
  // The weights sum to width^2 up to rounding; keep V within [0, 1] exactly.
  return std::clamp(sum / (widthTexels * widthTexels), 0.0f, 1.0f);
}

std::vector<Vec2> vogelDisk(int n) {
  std::vector<Vec2> pattern(static_cast<size_t>(std::max(n, 0)));
  const float goldenAngle = kPi * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    const float radius = std::sqrt((static_cast<float>(i) + 0.5f) / static_cast<float>(n));
    const float angle = static_cast<float>(i) * goldenAngle;
    pattern[static_cast<size_t>(i)] = radius * Vec2(std::cos(angle), std::sin(angle));
  }
  return pattern;
}

Vec2 pixelRotation(int x, int y) {
  const uint32_t h = hashCombine(static_cast<uint64_t>(static_cast<uint32_t>(x)), static_cast<uint64_t>(static_cast<uint32_t>(y)));
  const float angle = static_cast<float>(h) * (2.0f * kPi / 4294967296.0f);
  return Vec2(std::cos(angle), std::sin(angle));
}

namespace {

inline Vec2 rotate(const Vec2& p, const Vec2& rotation) {
  return Vec2(p.x * rotation.x - p.y * rotation.y, p.x * rotation.y + p.y * rotation.x);
}

}  // namespace

BlockerSearch searchBlockers(const LightMap& map, const ShadowReceiver& r, float radiusTexels,
                             std::span<const Vec2> pattern, const Vec2& rotation) {
  BlockerSearch result;
  float depthSum = 0.0f;
  for (const Vec2& p : pattern) {
    const Vec2 o = radiusTexels * rotate(p, rotation);
    const int i = static_cast<int>(std::floor(r.s + o.x));
    const int j = static_cast<int>(std::floor(r.t + o.y));
    if (i < 0 || j < 0 || i >= map.size || j >= map.size) continue;
    const float d = map.lsDepth(i, j);
    if (d < blockerThreshold(r, i, j)) {
      ++result.blockers;
      depthSum += d;
    }
  }
  if (result.blockers > 0) result.meanDepth = depthSum / static_cast<float>(result.blockers);
  return result;
}

float pcfDisk(const LightMap& map, const ShadowReceiver& r, float radiusTexels, std::span<const Vec2> pattern,
              const Vec2& rotation) {
  if (pattern.empty()) return 1.0f;
  float sum = 0.0f;
  for (const Vec2& p : pattern) {
    const Vec2 o = radiusTexels * rotate(p, rotation);
    // A 1-texel box at (s, t) + o: the four texels around it, bilinear weights.
    const float sc = r.s + o.x - 0.5f, tc = r.t + o.y - 0.5f;
    const float fs = std::floor(sc), ft = std::floor(tc);
    const int i = static_cast<int>(fs), j = static_cast<int>(ft);
    const float ws = sc - fs, wt = tc - ft;
    const float top = (1.0f - ws) * litAtTexel(map, r, i, j) + ws * litAtTexel(map, r, i + 1, j);
    const float bottom = (1.0f - ws) * litAtTexel(map, r, i, j + 1) + ws * litAtTexel(map, r, i + 1, j + 1);
    sum += (1.0f - wt) * top + wt * bottom;
  }
  return std::clamp(sum / static_cast<float>(pattern.size()), 0.0f, 1.0f);  // rounding of the weights
}

NearestBlocker findNearestBlocker(const LightMap& map, const ShadowReceiver& r, float maxRadiusTexels) {
  NearestBlocker best;
  if (!r.inMap) return best;
  const int ci = static_cast<int>(std::floor(r.s)), cj = static_cast<int>(std::floor(r.t));
  float bestDistance = kInfinity;
  const int maxRing = static_cast<int>(std::ceil(maxRadiusTexels)) + 1;
  for (int ring = 0; ring <= std::min(maxRing, 2 * map.size); ++ring) {
    // (s, t) lies in texel (ci, cj), within half a texel of its centre on each axis, so no texel of
    // this ring or beyond is nearer than ring - 0.5.
    const float ringMin = static_cast<float>(ring) - 0.5f;
    if (ringMin > bestDistance || ringMin > maxRadiusTexels) break;
    for (int dj = -ring; dj <= ring; ++dj) {
      const bool edgeRow = dj == -ring || dj == ring;
      const int step = edgeRow ? 1 : std::max(1, 2 * ring);
      for (int di = -ring; di <= ring; di += step) {
        const int i = ci + di, j = cj + dj;
        if (i < 0 || j < 0 || i >= map.size || j >= map.size) continue;
        const float d = map.lsDepth(i, j);
        if (!(d < blockerThreshold(r, i, j))) continue;
        const float ds = static_cast<float>(i) + 0.5f - r.s, dt = static_cast<float>(j) + 0.5f - r.t;
        const float distance = std::sqrt(ds * ds + dt * dt);
        if (distance <= maxRadiusTexels && distance < bestDistance) {
          bestDistance = distance;
          best.found = true;
          best.distanceTexels = distance;
          best.lsDepth = d;
          best.objectId = map.objectId.empty() ? kNoObject : map.objectId(i, j);
        }
      }
    }
  }
  return best;
}

}  // namespace penumbra
