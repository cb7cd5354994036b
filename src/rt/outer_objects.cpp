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
//
// The cone tests work on cosines and sines (cos(a + b) = cos a cos b - sin a sin b, every angle
// in [0, pi/2]), so building the buffer needs no trigonometric function; each rounding is covered
// by a slack that only adds entries. Cells' cones are computed only inside the 8 x 8 tiles some
// piece reaches (for `torus`, 65 of the 384 tiles).
//
// The per-ray loop reads a cell's list in blocks of kBlock capsules, branch-free, so the compiler
// turns each block into vector operations (CMakeLists.txt builds this file without errno for sqrt
// and with selects it may if-convert); the min combination keeps one running minimum per lane.
// Every lane computes exactly the scalar formulas, so V does not depend on the grid, the block
// size or the vector width.
#include "rt/outer_objects.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "penumbra/error.h"
#include "penumbra/mesh_topology.h"

// An 8-wide build of the per-ray loop beside the baseline's 4-wide one, chosen at run time, where
// the baseline has no AVX2 of its own.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__AVX2__)
#define PENUMBRA_OUTER_AVX2 1
#else
#define PENUMBRA_OUTER_AVX2 0
#endif

namespace penumbra::rt {
namespace {

// A cube face seen from its centre direction to a corner: cos and sin of acos(1 / sqrt(3)).
constexpr float kFaceCosHalf = 0.57735026918962576f;
constexpr float kFaceSinHalf = 0.81649658092772603f;
constexpr int kTile = 8;  // cells per side of the tiles that cull footprints before single cells
constexpr float kNoTau = std::numeric_limits<float>::max();
// Absorbs the rounding of the cone tests' cosines (a few float ulps of 1); being conservative only
// adds entries.
constexpr float kConeSlack = 1e-6f;

// Direction of cube-map face `face` at face coordinates (u, v) in [-1, 1], not normalized.
Vec3 faceDirection(int face, float u, float v) {
  const int axis = face / 2;
  Vec3 d;
  d[axis] = (face % 2 == 0) ? 1.0f : -1.0f;
  d[(axis + 1) % 3] = u;
  d[(axis + 2) % 3] = v;
  return d;
}

// A piece seen from the light's centre: unit direction, distance, and ball radius.
struct PieceView {
  Vec3 axis;
  float distance, reach;
};

// Cones of directions in structure-of-arrays form: unit axis, cos and sin of the half-angle (at
// most pi/2), and the largest distance from the light's centre to a scene point inside the cone
// (the receivers' A_max there).
struct ConeArrays {
  std::vector<float> ax, ay, az, cosHalf, sinHalf, maxDistance;
  explicit ConeArrays(size_t count)
      : ax(count), ay(count), az(count), cosHalf(count), sinHalf(count), maxDistance(count, 0.0f) {}
  void set(size_t i, const Vec3& axis, float c, float s, float distance) {
    ax[i] = axis.x;
    ay[i] = axis.y;
    az[i] = axis.z;
    cosHalf[i] = c;
    sinHalf[i] = s;
    maxDistance[i] = distance;
  }
};

// out[k] = whether rays through cone first + k can come within the piece's footprint y (the top of
// the file): no receiver there (maxDistance 0) -> no; the bound does not close (D >= A_max, or
// y >= |m - l|) -> yes; otherwise whether the piece's cone of reachable directions, asin(y / |m - l|)
// around its direction, overlaps the cone. Branch-free, so that the loop vectorizes.
void reachMask(const PieceView& piece, float diameter, const ConeArrays& cones, size_t first, size_t count,
               uint32_t* __restrict out) {
  const float* __restrict ax = cones.ax.data() + first;
  const float* __restrict ay = cones.ay.data() + first;
  const float* __restrict az = cones.az.data() + first;
  const float* __restrict cosHalf = cones.cosHalf.data() + first;
  const float* __restrict sinHalf = cones.sinHalf.data() + first;
  const float* __restrict maxDistance = cones.maxDistance.data() + first;
  const float px = piece.axis.x, py = piece.axis.y, pz = piece.axis.z, distance = piece.distance, reach = piece.reach;
  for (size_t k = 0; k < count; ++k) {
    // y <= (rp + R + D max(0, 1 - |m - l| / A_max)) / (1 - D / A_max).
    const float ratio = diameter / maxDistance[k];
    const float y = (reach + diameter * std::max(0.0f, 1.0f - distance / maxDistance[k])) / (1.0f - ratio);
    const float sinPiece = y / distance;
    const float cosPiece = std::sqrt(std::max(0.0f, (1.0f - sinPiece) * (1.0f + sinPiece)));
    const float dot = px * ax[k] + py * ay[k] + pz * az[k];
    const bool closes = (ratio < 1.0f) & (y < distance);
    const bool overlap = dot >= cosPiece * cosHalf[k] - sinPiece * sinHalf[k] - kConeSlack;
    out[k] = ((maxDistance[k] > 0.0f) & (!closes | overlap)) ? 1u : 0u;
  }
}

// A shadow ray as the per-ray loop reads it.
struct RayQuery {
  float ox, oy, oz, vx, vy, vz;
  float bScale;  //!< b = bScale t0: D / A, or D for a directional light
  float tLimit;  //!< A: capsules at or beyond the light's centre do not shadow
};

// The entries of the light buffer, as restrict pointers so the block loop vectorizes.
struct EntryView {
  const float* __restrict p0x;
  const float* __restrict p0y;
  const float* __restrict p0z;
  const float* __restrict ex;
  const float* __restrict ey;
  const float* __restrict ez;
  const float* __restrict radius;
};

// The entries from `first` on (whole pointers, so that a block's loads are contiguous vectors).
[[gnu::always_inline]] inline EntryView entriesFrom(const EntryView& e, uint32_t first) {
  return {e.p0x + first, e.p0y + first, e.p0z + first, e.ex + first, e.ey + first, e.ez + first, e.radius + first};
}

// tau of capsule j for the ray (kNoTau where the capsule does not shadow). The closest points of
// the ray's line and the capsule's segment, computed on the parts perpendicular to the ray
// (vectors, not differences of squares, which cancel when the ray passes close to a far point).
// Every operation runs whatever the capsule and the result is selected, so that a loop over
// capsules has no branch and vectorizes.
[[gnu::always_inline]] inline float capsuleTau(const EntryView& entries, uint32_t j, const RayQuery& r) {
  const float wx = entries.p0x[j] - r.ox, wy = entries.p0y[j] - r.oy, wz = entries.p0z[j] - r.oz;
  const float ex = entries.ex[j], ey = entries.ey[j], ez = entries.ez[j];
  const float wv = wx * r.vx + wy * r.vy + wz * r.vz;
  const float ev = ex * r.vx + ey * r.vy + ez * r.vz;
  const float wpx = wx - wv * r.vx, wpy = wy - wv * r.vy, wpz = wz - wv * r.vz;
  const float epx = ex - ev * r.vx, epy = ey - ev * r.vy, epz = ez - ev * r.vz;
  const float ee = epx * epx + epy * epy + epz * epz;
  const float we = wpx * epx + wpy * epy + wpz * epz;
  const float u = std::min(1.0f, std::max(0.0f, -we / std::max(ee, 1e-30f)));
  const float t0 = wv + u * ev;
  const float rx = wpx + u * epx, ry = wpy + u * epy, rz = wpz + u * epz;
  const float d = std::sqrt(rx * rx + ry * ry + rz * rz);
  const float q = (d - entries.radius[j]) / (r.bScale * t0);
  return ((t0 > 0.0f) & (t0 < r.tLimit)) ? q : kNoTau;
}

// tau of the kBlock capsules from `first`.
[[gnu::always_inline]] inline void blockTau(const EntryView& entries, uint32_t first, const RayQuery& r, float* __restrict tau) {
  const EntryView block = entriesFrom(entries, first);
  for (uint32_t j = 0; j < OuterObjects::kBlock; ++j) tau[j] = capsuleTau(block, j, r);
}

// The smallest tau over the blocks [begin, end). One running minimum per lane, std::min(lane, tau)
// written as the select that vectorizes (a compare and a blend); min is exact, so the result is
// the minimum over the list in any order.
[[gnu::always_inline]] inline float minTauOver(const EntryView& entries, uint32_t begin, uint32_t end, const RayQuery& ray) {
  alignas(32) float lanes[OuterObjects::kBlock];
  std::fill(lanes, lanes + OuterObjects::kBlock, kNoTau);
  for (uint32_t first = begin; first < end; first += OuterObjects::kBlock) {
    const EntryView block = entriesFrom(entries, first);
    for (uint32_t j = 0; j < OuterObjects::kBlock; ++j) {
      const float tau = capsuleTau(block, j, ray);
      lanes[j] = tau < lanes[j] ? tau : lanes[j];
    }
  }
  static_assert(OuterObjects::kBlock == 8);  // a reduction tree of three levels
  float half[4];
  for (int k = 0; k < 4; ++k) half[k] = std::min(lanes[k], lanes[k + 4]);
  return std::min(std::min(half[0], half[2]), std::min(half[1], half[3]));
}

// What the per-ray code reads of the light buffer, gathered once per batch of rays.
struct LightBufferView {
  bool directional;
  Vec3 frameX, frameY;  //!< directional: the grid plane's axes
  Vec2 gridLower;       //!< directional: grid origin in (x, y)
  float cellSize;       //!< directional: world units per cell
  int resolution;
  uint32_t catchAll;    //!< the cell that lists every capsule
  const uint32_t* cellStart;
  const uint32_t* cellCount;
  EntryView entries;
  float diameter;
};

// The cell of the ray from `origin` along `direction`: for a local light, the cube-map cell of the
// direction in which it leaves the light's centre; for a directional light, the grid cell of the
// origin's projection. The catch-all cell outside the grid.
[[gnu::always_inline]] inline uint32_t cellOf(const LightBufferView& view, const Vec3& origin, const Vec3& direction) {
  const int n = view.resolution;
  if (view.directional) {
    const float fx = std::floor((glm::dot(origin, view.frameX) - view.gridLower.x) / view.cellSize);
    const float fy = std::floor((glm::dot(origin, view.frameY) - view.gridLower.y) / view.cellSize);
    if (!(fx >= 0.0f && fx < static_cast<float>(n) && fy >= 0.0f && fy < static_cast<float>(n))) return view.catchAll;
    return static_cast<uint32_t>(static_cast<int>(fy) * n + static_cast<int>(fx));
  }
  const Vec3 w = -direction;
  const Vec3 a = glm::abs(w);
  const int axis = (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
  if (!(a[axis] > 0.0f)) return view.catchAll;
  const int face = 2 * axis + (w[axis] < 0.0f ? 1 : 0);
  const float u = w[(axis + 1) % 3] / a[axis], v = w[(axis + 2) % 3] / a[axis];
  const int x = std::clamp(static_cast<int>((u + 1.0f) * 0.5f * static_cast<float>(n)), 0, n - 1);
  const int y = std::clamp(static_cast<int>((v + 1.0f) * 0.5f * static_cast<float>(n)), 0, n - 1);
  return static_cast<uint32_t>((face * n + y) * n + x);
}

// b = D t0 / A (Appendix); A -> infinity with D per unit distance for a directional light.
[[gnu::always_inline]] inline RayQuery rayQuery(const LightBufferView& view, const Ray& ray, float distanceToLight) {
  return {ray.origin.x,
          ray.origin.y,
          ray.origin.z,
          ray.direction.x,
          ray.direction.y,
          ray.direction.z,
          view.directional ? view.diameter : view.diameter / distanceToLight,
          view.directional ? kInfinity : distanceToLight};
}

// s of each ray under the min combination: the falloff of the smallest tau in its cell's list.
// The cells first, then the capsule loops of the rays whose cell lists anything, one after the
// other: independent work that the CPU overlaps, with no branch on empty cells between them.
[[gnu::always_inline]] inline void minAttenuationsOver(const LightBufferView& view, const Ray* rays, const float* distanceToLight,
                                                       int count, OuterFalloff falloff, float* s) {
  constexpr int kBatch = 16;
  for (int first = 0; first < count; first += kBatch) {
    const int batch = std::min(kBatch, count - first);
    int listed[kBatch];
    uint32_t cells[kBatch];
    int busy = 0;
    for (int i = first; i < first + batch; ++i) {
      const uint32_t cell = cellOf(view, rays[i].origin, rays[i].direction);
      s[i] = 1.0f;
      listed[busy] = i;
      cells[busy] = cell;
      busy += view.cellCount[cell] != 0;
    }
    for (int k = 0; k < busy; ++k) {
      const int i = listed[k];
      const float minTau = minTauOver(view.entries, view.cellStart[cells[k]], view.cellStart[cells[k] + 1],
                                      rayQuery(view, rays[i], distanceToLight[i]));
      s[i] = minTau <= 0.0f ? 0.0f : outerFalloff(minTau, falloff);  // <= 0: inside an analytic sphere's inner object
    }
  }
}

void minAttenuations(const LightBufferView& view, const Ray* rays, const float* distanceToLight, int count,
                     OuterFalloff falloff, float* s) {
  minAttenuationsOver(view, rays, distanceToLight, count, falloff, s);
}

#if PENUMBRA_OUTER_AVX2
// The same compiled for 8-wide vectors, where the CPU has them: the same operations per lane (no
// multiply-add: CMakeLists.txt builds this file with -ffp-contract=off), so the same values.
[[gnu::target("avx2")]] void minAttenuationsAvx2(const LightBufferView& view, const Ray* rays, const float* distanceToLight,
                                                 int count, OuterFalloff falloff, float* s) {
  minAttenuationsOver(view, rays, distanceToLight, count, falloff, s);
}
#endif

// s of one ray under the product or sum combination: per object, the smallest tau over its
// capsules (an object's capsules are adjacent in every list), then the objects' s_i combined.
float combinedAttenuation(const LightBufferView& view, const int32_t* entryObject, const Ray& ray, float distanceToLight,
                          OuterFalloff falloff, OuterCombine combine) {
  const uint32_t cell = cellOf(view, ray.origin, ray.direction);
  const uint32_t count = view.cellCount[cell];
  if (count == 0) return 1.0f;
  const uint32_t begin = view.cellStart[cell], end = view.cellStart[cell + 1];
  const RayQuery query = rayQuery(view, ray, distanceToLight);
  float s = 1.0f;         // combined over finished objects
  int32_t object = -1;    // the object whose capsules are being read
  float objectTau = kNoTau;
  const auto finishObject = [&] {
    if (object < 0) return;
    const float si = outerFalloff(objectTau, falloff);
    s = combine == OuterCombine::Product ? s * si : s - (1.0f - si);
  };
  alignas(32) float tau[OuterObjects::kBlock];
  for (uint32_t block = begin; block < end; block += OuterObjects::kBlock) {
    blockTau(view.entries, block, query, tau);
    const uint32_t listed = std::min(OuterObjects::kBlock, begin + count - block);  // the padding is not read
    for (uint32_t j = 0; j < listed; ++j) {
      if (tau[j] <= 0.0f) return 0.0f;
      const int32_t o = entryObject[block + j];
      if (o != object) {
        finishObject();
        object = o;
        objectTau = kNoTau;
      }
      objectTau = std::min(objectTau, tau[j]);
    }
  }
  finishObject();
  return std::max(0.0f, s);
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
#if PENUMBRA_OUTER_AVX2
  avx2_ = __builtin_cpu_supports("avx2");
#endif

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
  float gridExtent = 0.0f;  // directional: side of the square the planar grid covers
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
    gridExtent = std::max(upper.x - lower.x, upper.y - lower.y);
  } else {
    for (const Vec3& c : corners) maxReceiverDistance_ = std::max(maxReceiverDistance_, glm::length(c - lightCenter_));
    maxReceiverDistance_ += margin;
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
    if (usesAnalyticSphere(object, options)) {
      capsules_.add(object.sphere->center, Vec3(0.0f), object.sphere->radius, index);
      analytic_[objectIndex] = true;
      ++analyticCount_;
      continue;
    }
    const Mesh& mesh = object.mesh;
    // Weld vertices at the same position (split normals or UV seams make duplicates), so that an
    // edge between two faces is found even when each face has its own copy of the vertices.
    const std::vector<uint32_t> weld = firstVertexAtSamePosition(mesh.positions);

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

  // Pieces of at most sceneRadius / 64 along each capsule, in capsule order.
  const float pieceLength = sceneRadius / 64.0f;
  std::vector<Piece> pieces;
  for (size_t c = 0; c < capsules_.size(); ++c) {
    const Vec3 p0(capsules_.p0x[c], capsules_.p0y[c], capsules_.p0z[c]);
    const Vec3 e(capsules_.ex[c], capsules_.ey[c], capsules_.ez[c]);
    const float length = glm::length(e);
    const int count = std::max(1, static_cast<int>(std::ceil(std::min(length / pieceLength, 1e6f))));
    const float rp = 0.5f * length / static_cast<float>(count);
    for (int k = 0; k < count; ++k)
      pieces.push_back({p0 + e * ((static_cast<float>(k) + 0.5f) / static_cast<float>(count)), rp + capsules_.radius[c],
                        static_cast<int>(c)});
  }

  // The light buffer: (cell, capsule) pairs from every piece's footprint (at the finest grid, up to
  // gridResolution, that keeps them within maxGridEntries), then compressed rows.
  std::vector<std::pair<int, int>> pairs;
  for (;;) {
    const size_t limit = resolution_ > 1 ? options.maxGridEntries : std::numeric_limits<size_t>::max();
    pairs.clear();
    bool within = true;
    if (directional_) {
      cellSize_ = gridExtent / static_cast<float>(resolution_);
      for (const Piece& piece : pieces) {
        insertDirectional(piece, pairs);
        if (pairs.size() > limit) {
          within = false;
          break;
        }
      }
    } else {
      within = insertLocal(bounds, margin, pieces, limit, pairs);
    }
    if (within) break;
    resolution_ /= 2;
  }
  const int cells = faceCount_ * resolution_ * resolution_;
  for (size_t c = 0; c < capsules_.size(); ++c) pairs.emplace_back(cells, static_cast<int>(c));  // the catch-all cell
  // Sorted by cell, then object, then capsule: per-object runs in each cell, duplicates adjacent.
  // Every cell's pairs arrive in capsule order (capsules were added object by object), so a stable
  // counting sort by cell gives that order in linear time (a comparison sort took seconds at 10^6
  // triangles).
  const size_t cellTotal = static_cast<size_t>(cells) + 1;
  {
    std::vector<uint32_t> start(cellTotal + 1, 0);
    for (const auto& [cell, capsule] : pairs) ++start[static_cast<size_t>(cell) + 1];
    for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
    std::vector<std::pair<int, int>> sorted(pairs.size());
    for (const auto& pair : pairs) sorted[start[static_cast<size_t>(pair.first)]++] = pair;
    pairs.swap(sorted);
  }
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  entryCount_ = pairs.size();
  cellCount_.assign(cellTotal, 0);
  for (const auto& [cell, capsule] : pairs) ++cellCount_[static_cast<size_t>(cell)];
  cellStart_.assign(cellTotal + 1, 0);
  for (size_t c = 0; c < cellTotal; ++c)
    cellStart_[c + 1] = cellStart_[c] + (cellCount_[c] + kBlock - 1) / kBlock * kBlock;
  // Padding: a point capsule of radius -infinity, whose tau is +infinity (or kNoTau) for every ray.
  const size_t padded = cellStart_.back();
  entryP0x_.assign(padded, 0.0f);
  entryP0y_.assign(padded, 0.0f);
  entryP0z_.assign(padded, 0.0f);
  entryEx_.assign(padded, 0.0f);
  entryEy_.assign(padded, 0.0f);
  entryEz_.assign(padded, 0.0f);
  entryRadius_.assign(padded, -kInfinity);
  entryObject_.assign(padded, -1);
  std::vector<uint32_t> next(cellStart_.begin(), cellStart_.end() - 1);
  for (const auto& [cell, capsule] : pairs) {
    const uint32_t i = next[static_cast<size_t>(cell)]++;
    const size_t c = static_cast<size_t>(capsule);
    entryP0x_[i] = capsules_.p0x[c];
    entryP0y_[i] = capsules_.p0y[c];
    entryP0z_[i] = capsules_.p0z[c];
    entryEx_[i] = capsules_.ex[c];
    entryEy_[i] = capsules_.ey[c];
    entryEz_[i] = capsules_.ez[c];
    entryRadius_[i] = capsules_.radius[c];
    entryObject_[i] = capsules_.object[c];
  }
}

void OuterObjects::insertDirectional(const Piece& piece, std::vector<std::pair<int, int>>& pairs) const {
  const int n = resolution_;
  const float depth = glm::dot(piece.center, frame_.z) - minReceiverDepth_;
  const float footprint = diameter_ < 1.0f ? (piece.reach + diameter_ * std::max(0.0f, depth)) / (1.0f - diameter_) : kInfinity;
  const Vec3 local = frame_.toLocal(piece.center);
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
    for (int x = x0; x <= x1; ++x) pairs.emplace_back(y * n + x, piece.capsule);
}

bool OuterObjects::insertLocal(const Bounds3& bounds, float margin, const std::vector<Piece>& pieces, size_t limit,
                               std::vector<std::pair<int, int>>& pairs) const {
  const int n = resolution_, tilesPerSide = (n + kTile - 1) / kTile, side = n + 1;
  const float step = 2.0f / static_cast<float>(n);
  // A point of the scene's box in direction w at distance r from the light has
  // r w_k <= upper_k - l_k (w_k > 0) or r (-w_k) <= l_k - lower_k (w_k < 0): over a cone whose
  // directions all lie on one side of an axis, |w_k| >= cos(angle(axis, +-e_k) + halfAngle), the
  // cosine of a sum expanded; the cosine is lowered by its rounding so that r stays an upper bound.
  const auto maxDistance = [&](const Vec3& axis, float cosHalf, float sinHalf) {
    float r = maxReceiverDistance_;
    if (bounds.empty()) return r;
    for (int k = 0; k < 3; ++k)
      for (const float sign : {1.0f, -1.0f}) {
        const float x = std::clamp(sign * axis[k], -1.0f, 1.0f);
        const float cosAngle = x * cosHalf - std::sqrt((1.0f - x) * (1.0f + x)) * sinHalf - kConeSlack;
        if (!(cosAngle > 0.0f)) continue;  // the cone reaches the plane w_k = 0: no bound from axis k
        const float room = sign > 0.0f ? bounds.upper[k] - lightCenter_[k] : lightCenter_[k] - bounds.lower[k];
        r = std::min(r, std::max(0.0f, room + margin) / cosAngle);
      }
    return r;
  };
  // Directions of the grid's vertices (normalized): the corners of cells and tiles. Every face's
  // are those of the +x face with their components permuted and signed.
  std::vector<Vec3> vertex(static_cast<size_t>(side * side));
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      vertex[static_cast<size_t>(y * side + x)] =
          glm::normalize(faceDirection(0, -1.0f + step * static_cast<float>(x), -1.0f + step * static_cast<float>(y)));
  const auto vertexDirection = [&](int face, int x, int y) {
    const Vec3& w = vertex[static_cast<size_t>(y * side + x)];
    const int axis = face / 2;
    Vec3 d;
    d[axis] = (face % 2 == 0) ? w.x : -w.x;
    d[(axis + 1) % 3] = w.y;
    d[(axis + 2) % 3] = w.z;
    return d;
  };
  // The cone of the face rectangle of cells [x0, x1) x [y0, y1), into `cones` at `index`: its
  // corners are the farthest directions from its centre's.
  const auto rectangleCone = [&](int face, int x0, int x1, int y0, int y1, ConeArrays& cones, size_t index) {
    const Vec3 axis = glm::normalize(faceDirection(face, -1.0f + 0.5f * step * static_cast<float>(x0 + x1),
                                                   -1.0f + 0.5f * step * static_cast<float>(y0 + y1)));
    float minCos = 1.0f;
    for (const int y : {y0, y1})
      for (const int x : {x0, x1})
        minCos = std::min(minCos, glm::dot(axis, vertexDirection(face, x, y)));
    const float cosHalf = std::clamp(minCos, 0.0f, 1.0f);
    const float sinHalf = std::sqrt((1.0f - cosHalf) * (1.0f + cosHalf));
    cones.set(index, axis, cosHalf, sinHalf, maxDistance(axis, cosHalf, sinHalf));
  };

  std::vector<PieceView> views(pieces.size());
  for (size_t p = 0; p < pieces.size(); ++p) {
    const Vec3 toPiece = pieces[p].center - lightCenter_;
    const float distance = glm::length(toPiece);
    views[p] = {distance > 0.0f ? toPiece / distance : Vec3(0.0f, 0.0f, 1.0f), distance, pieces[p].reach};
  }
  // Faces, then tiles: the (tile, piece) candidates in piece order.
  const size_t tilesPerFace = static_cast<size_t>(tilesPerSide * tilesPerSide);
  ConeArrays faces(6), tiles(6 * tilesPerFace);
  for (int face = 0; face < 6; ++face) {
    Vec3 axis(0.0f);
    axis[face / 2] = (face % 2 == 0) ? 1.0f : -1.0f;
    faces.set(static_cast<size_t>(face), axis, kFaceCosHalf, kFaceSinHalf, maxReceiverDistance_);
    for (int ty = 0; ty < tilesPerSide; ++ty)
      for (int tx = 0; tx < tilesPerSide; ++tx)
        rectangleCone(face, tx * kTile, std::min(n, (tx + 1) * kTile), ty * kTile, std::min(n, (ty + 1) * kTile), tiles,
                      static_cast<size_t>(face) * tilesPerFace + static_cast<size_t>(ty * tilesPerSide + tx));
  }
  std::vector<uint32_t> reached(std::max<size_t>(tilesPerFace, kTile * kTile));
  std::vector<std::pair<int, int>> candidates;
  for (size_t p = 0; p < pieces.size(); ++p) {
    uint32_t faceReached[6];
    reachMask(views[p], diameter_, faces, 0, 6, faceReached);
    for (int face = 0; face < 6; ++face) {
      if (!faceReached[face]) continue;
      const size_t first = static_cast<size_t>(face) * tilesPerFace;
      reachMask(views[p], diameter_, tiles, first, tilesPerFace, reached.data());
      for (size_t t = 0; t < tilesPerFace; ++t)
        if (reached[t]) candidates.emplace_back(static_cast<int>(first + t), static_cast<int>(p));
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // Cells, only in the tiles some piece reaches; per tile, each cell's pairs in piece order. Cells
  // of a tile cut by the face's edge keep maxDistance 0: never reached.
  ConeArrays cells(kTile * kTile);
  for (size_t i = 0; i < candidates.size();) {
    const int tile = candidates[i].first;
    size_t j = i;
    while (j < candidates.size() && candidates[j].first == tile) ++j;
    const int face = tile / static_cast<int>(tilesPerFace), inFace = tile % static_cast<int>(tilesPerFace);
    const int x0 = (inFace % tilesPerSide) * kTile, y0 = (inFace / tilesPerSide) * kTile;
    const int x1 = std::min(n, x0 + kTile), y1 = std::min(n, y0 + kTile);
    std::fill(cells.maxDistance.begin(), cells.maxDistance.end(), 0.0f);
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) rectangleCone(face, x, x + 1, y, y + 1, cells, static_cast<size_t>((y - y0) * kTile + (x - x0)));
    for (; i < j; ++i) {
      const size_t p = static_cast<size_t>(candidates[i].second);
      reachMask(views[p], diameter_, cells, 0, kTile * kTile, reached.data());
      for (int k = 0; k < kTile * kTile; ++k)
        if (reached[static_cast<size_t>(k)]) pairs.emplace_back((face * n + y0 + k / kTile) * n + x0 + k % kTile, pieces[p].capsule);
      if (pairs.size() > limit) return false;
    }
  }
  return true;
}

void OuterObjects::attenuations(const Ray* rays, const float* distanceToLight, int count, OuterFalloff falloff,
                                OuterCombine combine, float* s) const {
  LightBufferView view;
  view.directional = directional_;
  view.frameX = frame_.x;
  view.frameY = frame_.y;
  view.gridLower = gridLower_;
  view.cellSize = cellSize_;
  view.resolution = resolution_;
  view.catchAll = static_cast<uint32_t>(faceCount_ * resolution_ * resolution_);
  view.cellStart = cellStart_.data();
  view.cellCount = cellCount_.data();
  view.entries = {entryP0x_.data(), entryP0y_.data(), entryP0z_.data(), entryEx_.data(),
                  entryEy_.data(),  entryEz_.data(),  entryRadius_.data()};
  view.diameter = diameter_;
  if (combine == OuterCombine::Min) {
#if PENUMBRA_OUTER_AVX2
    if (avx2_) {
      minAttenuationsAvx2(view, rays, distanceToLight, count, falloff, s);
      return;
    }
#endif
    minAttenuations(view, rays, distanceToLight, count, falloff, s);
    return;
  }
  for (int i = 0; i < count; ++i) s[i] = combinedAttenuation(view, entryObject_.data(), rays[i], distanceToLight[i], falloff, combine);
}

float OuterObjects::attenuation(const Vec3& origin, const Vec3& direction, float distanceToLight, OuterFalloff falloff,
                                OuterCombine combine) const {
  Ray ray;
  ray.origin = origin;
  ray.direction = direction;
  float s = 1.0f;
  attenuations(&ray, &distanceToLight, 1, falloff, combine, &s);
  return s;
}

}  // namespace penumbra::rt
