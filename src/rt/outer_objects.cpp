// Outer objects and their light buffer (see outer_objects.h for the model and the paper).
//
// Conservative footprints. A capsule can change s of a shadow ray only if some ray point q lies
// within R + b of it (b = D t0 / A). Split into pieces of bounding radius rp around centres m, a
// piece is touched only by rays passing within y = rp + R + b of m. For a local light A <= A_max
// (the farthest point of the scene's box from the light's centre in the directions of the cell or
// tile being tested: receivers are scene points) and q lies between the receiver and the light,
// so b = D (1 - |q - l| / A) <= D (1 - (|m - l| - y) / A_max); hence
//     y <= (rp + R + D max(0, 1 - |m - l| / A_max)) / (1 - D / A_max),
// and every such ray leaves the light in a direction within asin(y / |m - l|) of m's: the cube-map
// cells whose direction cones come that close list the capsule. For a directional light the same
// argument with b = D t0, t0 <= z(m) + y - z_min gives y <= (rp + R + D max(0, z(m) - z_min)) / (1 - D)
// as a radius around m's projection on the grid plane. Where the bound does not close (D >= A_max,
// y >= |m - l|) the capsule goes into every cell: still exact, only slower.
#include "rt/outer_objects.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "penumbra/error.h"

namespace penumbra::rt {
namespace {

// Half-angle of a cube face seen from its centre direction to a corner: acos(1 / sqrt(3)).
constexpr float kFaceHalfAngle = 0.9553166181245093f;
constexpr int kTile = 8;  // cells per side of the tiles that cull footprints before single cells
constexpr float kNoTau = std::numeric_limits<float>::max();

// Direction of cube-map face `face` at face coordinates (u, v) in [-1, 1], not normalized.
Vec3 faceDirection(int face, float u, float v) {
  const int axis = face / 2;
  Vec3 d;
  d[axis] = (face % 2 == 0) ? 1.0f : -1.0f;
  d[(axis + 1) % 3] = u;
  d[(axis + 2) % 3] = v;
  return d;
}

// The direction cone of the face rectangle [u0, u1] x [v0, v1]: unit axis and cos of its half-angle
// (the largest angle from the axis to a corner; the corners are the farthest points of the rectangle).
struct DirectionCone {
  Vec3 axis;
  float halfAngle;
};
DirectionCone rectangleCone(int face, float u0, float u1, float v0, float v1) {
  DirectionCone cone;
  cone.axis = glm::normalize(faceDirection(face, 0.5f * (u0 + u1), 0.5f * (v0 + v1)));
  float minCos = 1.0f;
  for (const float u : {u0, u1})
    for (const float v : {v0, v1}) minCos = std::min(minCos, glm::dot(cone.axis, glm::normalize(faceDirection(face, u, v))));
  cone.halfAngle = std::acos(std::clamp(minCos, -1.0f, 1.0f));
  return cone;
}

bool conesOverlap(const Vec3& axisA, float halfAngleA, const Vec3& axisB, float halfAngleB) {
  const float sum = halfAngleA + halfAngleB;
  if (sum >= kPi) return true;
  // A small slack absorbs the rounding of the cosines; being conservative only adds entries.
  return glm::dot(axisA, axisB) >= std::cos(sum) - 1e-6f;
}

// Exact float bits of a position, so welding merges only vertices at the same place.
std::array<uint32_t, 3> positionBits(const Vec3& p) {
  std::array<uint32_t, 3> bits;
  for (int k = 0; k < 3; ++k) {
    const float f = p[k] == 0.0f ? 0.0f : p[k];  // -0 and +0 are the same place
    std::memcpy(&bits[k], &f, sizeof(float));
  }
  return bits;
}

}  // namespace

void OuterObjects::Capsules::add(const Vec3& p0, const Vec3& e, float r, int32_t objectIndex) {
  p0x.push_back(p0.x);
  p0y.push_back(p0.y);
  p0z.push_back(p0.z);
  ex.push_back(e.x);
  ey.push_back(e.y);
  ez.push_back(e.z);
  radius.push_back(r);
  object.push_back(objectIndex);
}

OuterObjects::OuterObjects(const Scene& scene, const Light& light, const OuterObjectOptions& options) {
  if (!(options.lightDiameter > 0.0f) || !std::isfinite(options.lightDiameter))
    fail("parker: light diameter must be a finite number > 0, got {}", options.lightDiameter);
  if (options.gridResolution < 1) fail("parker: grid resolution must be >= 1, got {}", options.gridResolution);
  directional_ = light.isDirectional();
  lightCenter_ = light.center();
  diameter_ = options.lightDiameter;
  resolution_ = options.gridResolution;
  faceCount_ = directional_ ? 1 : 6;

  const Bounds3 bounds = scene.bounds();
  const float sceneRadius = bounds.empty() ? 1.0f : std::max(bounds.radius(), 1e-6f);
  // Receivers lie in the scene's bounds; shadow-ray origins are offset from them by 1e-4 of the
  // scene's scale (shadowRayEpsilon), far inside this margin.
  const float margin = 1e-3f * sceneRadius;
  std::array<Vec3, 8> corners;
  for (int i = 0; i < 8; ++i)
    corners[i] = bounds.empty() ? lightCenter_
                                : Vec3((i & 1) ? bounds.upper.x : bounds.lower.x, (i & 2) ? bounds.upper.y : bounds.lower.y,
                                       (i & 4) ? bounds.upper.z : bounds.lower.z);
  if (directional_) {
    frame_ = Frame::fromZ(light.direction());
    Vec2 lower(kInfinity), upper(-kInfinity);
    minReceiverDepth_ = kInfinity;
    for (const Vec3& c : corners) {
      const Vec3 local = frame_.toLocal(c);
      lower = glm::min(lower, Vec2(local));
      upper = glm::max(upper, Vec2(local));
      minReceiverDepth_ = std::min(minReceiverDepth_, local.z);
    }
    lower -= Vec2(margin);
    upper += Vec2(margin);
    minReceiverDepth_ -= margin;
    gridLower_ = lower;
    cellSize_ = std::max(upper.x - lower.x, upper.y - lower.y) / static_cast<float>(resolution_);
  } else {
    for (const Vec3& c : corners) maxReceiverDistance_ = std::max(maxReceiverDistance_, glm::length(c - lightCenter_));
    maxReceiverDistance_ += margin;
    // A point of the scene's box in direction w at distance r from the light has
    // r w_k <= upper_k - l_k (w_k > 0) or r (-w_k) <= l_k - lower_k (w_k < 0): over a cone whose
    // directions all lie on one side of an axis, |w_k| >= cos(angle(axis, +-e_k) + halfAngle).
    const auto maxDistance = [&](const Vec3& axis, float halfAngle) {
      float r = maxReceiverDistance_;
      if (bounds.empty()) return r;
      for (int k = 0; k < 3; ++k)
        for (const float sign : {1.0f, -1.0f}) {
          const float angle = std::acos(std::clamp(sign * axis[k], -1.0f, 1.0f)) + halfAngle;
          if (angle >= 0.5f * kPi) continue;
          const float room = sign > 0.0f ? bounds.upper[k] - lightCenter_[k] : lightCenter_[k] - bounds.lower[k];
          r = std::min(r, std::max(0.0f, room + margin) / std::cos(angle));
        }
      return r;
    };
    const int n = resolution_, tilesPerSide = (n + kTile - 1) / kTile;
    const float step = 2.0f / static_cast<float>(n);
    const auto add = [&](Cones& cones, int face, int x0, int x1, int y0, int y1) {
      const DirectionCone cone = rectangleCone(face, -1.0f + step * x0, -1.0f + step * x1, -1.0f + step * y0, -1.0f + step * y1);
      cones.axis.push_back(cone.axis);
      cones.halfAngle.push_back(cone.halfAngle);
      cones.maxDistance.push_back(maxDistance(cone.axis, cone.halfAngle));
    };
    for (int face = 0; face < 6; ++face) {
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) add(cells_, face, x, x + 1, y, y + 1);
      for (int ty = 0; ty < tilesPerSide; ++ty)
        for (int tx = 0; tx < tilesPerSide; ++tx)
          add(tiles_, face, tx * kTile, std::min(n, (tx + 1) * kTile), ty * kTile, std::min(n, (ty + 1) * kTile));
    }
  }

  // Capsules: analytic spheres, then every mesh's silhouette edges.
  analytic_.assign(scene.objects.size(), false);
  struct EdgeRecord {
    uint64_t key;      // welded vertex ids (low, high)
    uint32_t a, b;     // the edge's vertex indices in the mesh
    bool front;        // the face faces the light's centre
  };
  std::vector<EdgeRecord> edges;
  for (size_t objectIndex = 0; objectIndex < scene.objects.size(); ++objectIndex) {
    const Object& object = scene.objects[objectIndex];
    const int32_t index = static_cast<int32_t>(objectIndex);
    if (options.analyticSpheres && object.sphere) {
      capsules_.add(object.sphere->center, Vec3(0.0f), object.sphere->radius, index);
      analytic_[objectIndex] = true;
      ++analyticCount_;
      continue;
    }
    const Mesh& mesh = object.mesh;
    // Weld vertices at the same position (split normals or UV seams make duplicates), so that an
    // edge between two faces is found even when each face has its own copy of the vertices.
    std::vector<uint32_t> order(mesh.positions.size());
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return positionBits(mesh.positions[x]) < positionBits(mesh.positions[y]); });
    std::vector<uint32_t> weld(mesh.positions.size());
    for (size_t i = 0; i < order.size(); ++i)
      weld[order[i]] = (i > 0 && positionBits(mesh.positions[order[i]]) == positionBits(mesh.positions[order[i - 1]])) ? weld[order[i - 1]] : order[i];

    edges.clear();
    edges.reserve(3 * mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::uvec3& tri = mesh.triangles[t];
      if (tri.x >= mesh.positions.size() || tri.y >= mesh.positions.size() || tri.z >= mesh.positions.size())
        fail("{}: object '{}' triangle {} uses vertex index {} but the mesh has {} vertices", scene.source, object.name, t,
             std::max({tri.x, tri.y, tri.z}), mesh.positions.size());
      const Vec3 p0 = mesh.positions[tri.x], p1 = mesh.positions[tri.y], p2 = mesh.positions[tri.z];
      const Vec3 n = glm::cross(p1 - p0, p2 - p0);
      const float n2 = glm::dot(n, n);
      if (!(n2 > 0.0f) || !std::isfinite(n2) || !isFinite(p0) || !isFinite(p1) || !isFinite(p2)) continue;  // cannot be hit
      const bool front = glm::dot(n, directional_ ? light.direction() : lightCenter_ - p0) > 0.0f;
      const uint32_t v[3] = {tri.x, tri.y, tri.z};
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = v[k], b = v[(k + 1) % 3];
        const uint64_t wa = weld[a], wb = weld[b];
        if (wa == wb) continue;
        edges.push_back({std::min(wa, wb) << 32 | std::max(wa, wb), a, b, front});
      }
    }
    std::sort(edges.begin(), edges.end(), [](const EdgeRecord& x, const EdgeRecord& y) { return x.key < y.key; });
    for (size_t i = 0; i < edges.size();) {
      size_t j = i + 1;
      while (j < edges.size() && edges[j].key == edges[i].key) ++j;
      // An open boundary (one face), a silhouette (two faces, one towards the light) or a
      // non-manifold edge (three or more faces: its outline status is ambiguous, so it is kept).
      const bool keep = (j - i != 2) || edges[i].front != edges[i + 1].front;
      if (keep) {
        const Vec3 a = mesh.positions[edges[i].a];
        capsules_.add(a, mesh.positions[edges[i].b] - a, 0.0f, index);
        ++edgeCount_;
      }
      i = j;
    }
  }

  // The light buffer: (cell, capsule) pairs from every piece's footprint, then compressed rows.
  const int cells = faceCount_ * resolution_ * resolution_;
  const float pieceLength = sceneRadius / 64.0f;
  std::vector<std::pair<int, int>> pairs;
  for (size_t c = 0; c < capsules_.size(); ++c) {
    const Vec3 p0(capsules_.p0x[c], capsules_.p0y[c], capsules_.p0z[c]);
    const Vec3 e(capsules_.ex[c], capsules_.ey[c], capsules_.ez[c]);
    const float length = glm::length(e);
    const int pieces = std::max(1, static_cast<int>(std::ceil(std::min(length / pieceLength, 1e6f))));
    const float rp = 0.5f * length / static_cast<float>(pieces);
    for (int k = 0; k < pieces; ++k) {
      const Vec3 m = p0 + e * ((static_cast<float>(k) + 0.5f) / static_cast<float>(pieces));
      insert(static_cast<int>(c), m, rp + capsules_.radius[c], pairs);
    }
  }
  for (size_t c = 0; c < capsules_.size(); ++c) pairs.emplace_back(cells, static_cast<int>(c));  // the catch-all cell
  // Sorted by cell, then object, then capsule: per-object runs in each cell, duplicates adjacent.
  // Capsules were added object by object and the pairs in capsule order, so a stable counting sort
  // by cell gives that order in linear time (a comparison sort took seconds at 10^6 triangles).
  cellStart_.assign(static_cast<size_t>(cells) + 2, 0);
  for (const auto& [cell, capsule] : pairs) ++cellStart_[static_cast<size_t>(cell) + 1];
  for (size_t i = 1; i < cellStart_.size(); ++i) cellStart_[i] += cellStart_[i - 1];
  {
    std::vector<std::pair<int, int>> sorted(pairs.size());
    std::vector<uint32_t> next(cellStart_.begin(), cellStart_.end() - 1);
    for (const auto& pair : pairs) sorted[next[static_cast<size_t>(pair.first)]++] = pair;
    pairs.swap(sorted);
  }
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  cellStart_.assign(static_cast<size_t>(cells) + 2, 0);
  for (const auto& [cell, capsule] : pairs) ++cellStart_[static_cast<size_t>(cell) + 1];
  for (size_t i = 1; i < cellStart_.size(); ++i) cellStart_[i] += cellStart_[i - 1];
  const auto copy = [&](const std::vector<float>& from, std::vector<float>& to) {
    to.resize(pairs.size());
    for (size_t i = 0; i < pairs.size(); ++i) to[i] = from[pairs[i].second];
  };
  copy(capsules_.p0x, entryP0x_);
  copy(capsules_.p0y, entryP0y_);
  copy(capsules_.p0z, entryP0z_);
  copy(capsules_.ex, entryEx_);
  copy(capsules_.ey, entryEy_);
  copy(capsules_.ez, entryEz_);
  copy(capsules_.radius, entryRadius_);
  entryObject_.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) entryObject_[i] = capsules_.object[pairs[i].second];
}

float OuterObjects::footprint(float reach, float distance, float maxDistance) const {
  // y <= (rp + R + D max(0, 1 - |m - l| / A_max)) / (1 - D / A_max), see the top of the file.
  const float ratio = diameter_ / maxDistance;
  if (!(ratio < 1.0f)) return kInfinity;
  return (reach + diameter_ * std::max(0.0f, 1.0f - distance / maxDistance)) / (1.0f - ratio);
}

void OuterObjects::insert(int capsule, const Vec3& center, float reach, std::vector<std::pair<int, int>>& pairs) const {
  const int n = resolution_;
  if (directional_) {
    const float depth = glm::dot(center, frame_.z) - minReceiverDepth_;
    const float footprint = diameter_ < 1.0f ? (reach + diameter_ * std::max(0.0f, depth)) / (1.0f - diameter_) : kInfinity;
    const Vec3 local = frame_.toLocal(center);
    const bool everywhere = !std::isfinite(footprint);
    const auto cellRange = [&](float c, float lower) {
      if (everywhere) return std::pair<int, int>(0, n - 1);
      const float lo = std::floor((c - footprint - lower) / cellSize_), hi = std::floor((c + footprint - lower) / cellSize_);
      return std::pair<int, int>(static_cast<int>(std::clamp(lo, 0.0f, static_cast<float>(n - 1))),
                                 static_cast<int>(std::clamp(hi, 0.0f, static_cast<float>(n - 1))));
    };
    const auto [x0, x1] = cellRange(local.x, gridLower_.x);
    const auto [y0, y1] = cellRange(local.y, gridLower_.y);
    if (!everywhere && (local.x + footprint < gridLower_.x || local.y + footprint < gridLower_.y ||
                        local.x - footprint > gridLower_.x + n * cellSize_ || local.y - footprint > gridLower_.y + n * cellSize_))
      return;  // no receiver's ray comes near it
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) pairs.emplace_back(y * n + x, capsule);
    return;
  }
  const Vec3 toPiece = center - lightCenter_;
  const float distance = glm::length(toPiece);
  const Vec3 axis = distance > 0.0f ? toPiece / distance : Vec3(0.0f, 0.0f, 1.0f);
  // The piece's cone of reachable directions for receivers no farther than maxDistance.
  const auto reaches = [&](const Vec3& coneAxis, float coneHalfAngle, float maxDistance) {
    if (!(maxDistance > 0.0f)) return false;  // no scene point in these directions: no receiver
    const float y = footprint(reach, distance, maxDistance);
    if (!(y < distance)) return true;
    return conesOverlap(axis, std::asin(y / distance), coneAxis, coneHalfAngle);
  };
  const int tilesPerSide = (n + kTile - 1) / kTile;
  for (int face = 0; face < 6; ++face) {
    const int axisIndex = face / 2;
    Vec3 faceAxis(0.0f);
    faceAxis[axisIndex] = (face % 2 == 0) ? 1.0f : -1.0f;
    if (!reaches(faceAxis, kFaceHalfAngle, maxReceiverDistance_)) continue;
    for (int ty = 0; ty < tilesPerSide; ++ty)
      for (int tx = 0; tx < tilesPerSide; ++tx) {
        const size_t tile = (static_cast<size_t>(face) * tilesPerSide + ty) * tilesPerSide + tx;
        if (!reaches(tiles_.axis[tile], tiles_.halfAngle[tile], tiles_.maxDistance[tile])) continue;
        for (int y = ty * kTile; y < std::min(n, (ty + 1) * kTile); ++y)
          for (int x = tx * kTile; x < std::min(n, (tx + 1) * kTile); ++x) {
            const int cell = (face * n + y) * n + x;
            if (reaches(cells_.axis[cell], cells_.halfAngle[cell], cells_.maxDistance[cell])) pairs.emplace_back(cell, capsule);
          }
      }
  }
}

int OuterObjects::cellOf(const Vec3& origin, const Vec3& direction) const {
  const int n = resolution_;
  if (directional_) {
    const float fx = std::floor((glm::dot(origin, frame_.x) - gridLower_.x) / cellSize_);
    const float fy = std::floor((glm::dot(origin, frame_.y) - gridLower_.y) / cellSize_);
    if (!(fx >= 0.0f && fx < static_cast<float>(n) && fy >= 0.0f && fy < static_cast<float>(n))) return -1;
    return static_cast<int>(fy) * n + static_cast<int>(fx);
  }
  // The direction in which the ray leaves the light: from the light's centre towards the receiver.
  const Vec3 w = -direction;
  const Vec3 a = glm::abs(w);
  const int axis = (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
  if (!(a[axis] > 0.0f)) return -1;
  const int face = 2 * axis + (w[axis] < 0.0f ? 1 : 0);
  const float u = w[(axis + 1) % 3] / a[axis], v = w[(axis + 2) % 3] / a[axis];
  const int x = std::clamp(static_cast<int>((u + 1.0f) * 0.5f * static_cast<float>(n)), 0, n - 1);
  const int y = std::clamp(static_cast<int>((v + 1.0f) * 0.5f * static_cast<float>(n)), 0, n - 1);
  return (face * n + y) * n + x;
}

float OuterObjects::attenuation(const Vec3& origin, const Vec3& direction, float distanceToLight, OuterFalloff falloff,
                                OuterCombine combine) const {
  int cell = cellOf(origin, direction);
  if (cell < 0) cell = faceCount_ * resolution_ * resolution_;
  const uint32_t begin = cellStart_[static_cast<size_t>(cell)], end = cellStart_[static_cast<size_t>(cell) + 1];
  if (begin == end) return 1.0f;

  // b = D t0 / A (Appendix); A -> infinity with D per unit distance for a directional light.
  const float bScale = directional_ ? diameter_ : diameter_ / distanceToLight;
  const float tLimit = directional_ ? kInfinity : distanceToLight;
  const float ox = origin.x, oy = origin.y, oz = origin.z;
  const float vx = direction.x, vy = direction.y, vz = direction.z;

  constexpr uint32_t kChunk = 64;
  alignas(64) float tau[kChunk];
  float s = 1.0f;              // combined over finished objects
  float minTau = kNoTau;       // min: over every capsule
  int32_t object = -1;         // product / sum: the object whose capsules are being read
  float objectTau = kNoTau;
  const auto finishObject = [&] {
    if (object < 0) return;
    const float si = outerFalloff(objectTau, falloff);
    s = combine == OuterCombine::Product ? s * si : s - (1.0f - si);
  };
  for (uint32_t chunk = begin; chunk < end; chunk += kChunk) {
    const uint32_t count = std::min(kChunk, end - chunk);
    const float* __restrict p0x = entryP0x_.data() + chunk;
    const float* __restrict p0y = entryP0y_.data() + chunk;
    const float* __restrict p0z = entryP0z_.data() + chunk;
    const float* __restrict ex = entryEx_.data() + chunk;
    const float* __restrict ey = entryEy_.data() + chunk;
    const float* __restrict ez = entryEz_.data() + chunk;
    const float* __restrict radius = entryRadius_.data() + chunk;
    // The closest points of the ray's line and each capsule's segment, computed on the parts
    // perpendicular to the ray (vectors, not differences of squares, which cancel when the ray
    // passes close to a far point). Branch-free so that the loop vectorizes.
    for (uint32_t j = 0; j < count; ++j) {
      const float wx = p0x[j] - ox, wy = p0y[j] - oy, wz = p0z[j] - oz;
      const float wv = wx * vx + wy * vy + wz * vz;
      const float ev = ex[j] * vx + ey[j] * vy + ez[j] * vz;
      const float wpx = wx - wv * vx, wpy = wy - wv * vy, wpz = wz - wv * vz;
      const float epx = ex[j] - ev * vx, epy = ey[j] - ev * vy, epz = ez[j] - ev * vz;
      const float ee = epx * epx + epy * epy + epz * epz;
      const float we = wpx * epx + wpy * epy + wpz * epz;
      const float u = std::min(1.0f, std::max(0.0f, -we / std::max(ee, 1e-30f)));
      const float t0 = wv + u * ev;
      const float rx = wpx + u * epx, ry = wpy + u * epy, rz = wpz + u * epz;
      const float d = std::sqrt(rx * rx + ry * ry + rz * rz);
      const bool valid = t0 > 0.0f && t0 < tLimit;
      tau[j] = valid ? (d - radius[j]) / (bScale * t0) : kNoTau;
    }
    if (combine == OuterCombine::Min) {
      for (uint32_t j = 0; j < count; ++j) minTau = std::min(minTau, tau[j]);
      if (minTau <= 0.0f) return 0.0f;  // inside an analytic sphere's inner object
      continue;
    }
    for (uint32_t j = 0; j < count; ++j) {
      if (tau[j] <= 0.0f) return 0.0f;
      const int32_t o = entryObject_[chunk + j];
      if (o != object) {
        finishObject();
        object = o;
        objectTau = kNoTau;
      }
      objectTau = std::min(objectTau, tau[j]);
    }
  }
  if (combine == OuterCombine::Min) return outerFalloff(minTau, falloff);
  finishObject();
  return std::max(0.0f, s);
}

}  // namespace penumbra::rt
