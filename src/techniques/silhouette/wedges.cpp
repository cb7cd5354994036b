// `wedges`: penumbra wedges / soft shadow volumes (Assarsson & Akenine-Moeller 2003, "A
// geometry-based soft shadow volume algorithm using graphics hardware"), the baseline of Rouf 2007
// (Sections 2.4.1, 2.5 and 4.4.1.1), in software, per camera pixel. A concave polygon light runs as
// its fewest convex parts, V combined by area, as for ssv (convex_parts.h).
//
// The silhouette is computed once, from the light's centre only (the boundary of the facets that
// face the centre, mesh_topology.h), and split into rings. For a receiver p every silhouette edge is
// projected from p onto the light's plane and its coverage of the light is measured: the area of
// the light inside the triangle (centre, a', b') spanned by the light's centre and the projected
// edge, signed by its orientation, exact for any convex polygon. It is read off the light's
// sectors where it can be (LightSectors, stages.h): an edge projected inside the light covers its
// own triangle, and a chain of edges projected outside it covers the light's sector between the
// chain's ends (plus the whole light at each turn around the centre); only an edge that crosses
// the light's outline has the polygon clipped to its triangle. Summed over a closed ring this is the light's area
// inside the projected silhouette, counted with its winding: the hard shadow of the centre (the winding at the centre)
// plus the wedge corrections of every edge whose projection crosses the light (the triangles' parts beyond the
// projected edge), which is how the paper splits it. Contributions of all rings and objects are simply added (the
// "overlap approximation", Fig. 2-12), and the occluded fraction is clamped to [0, 1]: V = 1 - clamp(sum / area).
//
// The two approximations the thesis criticizes are therefore present on purpose: the
// single-silhouette artifact (the silhouette seen from the centre is used for every point of the
// light, Fig. 2-15 / 4-10) and the overlap approximation (Fig. 2-12 / 4-13).
//
// Occluders that are not closed 2-manifolds (our extension; the paper assumes solids): any mesh
// becomes a closed oriented surface (mesh_topology.h), its closed components solids, the rest
// doubled shells (each triangle and its reversed copy, the shell wound consistently where it can
// be). The facets of a shell that face the centre are its front sides in one place and its back
// sides in another (a sphere with a hole, wound outwards: the outside of its upper half, the
// inside of its lower half), and where the shell encloses space (that sphere, an open box) both
// layers cover the same part of the light: added, the coverage would count that part twice. So the silhouette is taken
// per layer, the solids', the shells' front sides' and their back sides', and an object's coverage is its solids' plus
// the larger of its two shell layers'. Two layers of one object that cover different parts of the light from p (two
// separate open pieces, one seen from each side) are then counted as the larger one only.
//
// Other choices: each ring is clipped as a closed polygon to z < z_p (1 - 1e-4) (only occluder parts
// nearer to the light than p can occlude it) and to the light's plane. Where the ring passes beyond
// p (p on or beside an occluder) or behind the light's plane, the cut is closed along that plane;
// the closing segment projects far outside the light and could pass around it either way, which
// changes the ring's winding around the centre by one but not its wedge corrections. For such a
// ring the hard-shadow part comes from the paper's shadow-volume pass instead, done here as one
// ray from p to the light's centre (the offset rule of src/rt/shadow_ray.h): the ring hides the
// centre when the first thing the ray meets is the ring's object. (For whole rings the winding is
// kept: the ray and the winding could disagree in the last bit where the centre lies on a
// projected edge, and V would jump there.) A two-sided planar sheet (mesh_topology.h) does not
// shadow its own pixels; receivers behind the light's plane are
// handled in the light space of its other face; rings are binned in the light-space grid of stages.h
// by their regions of influence (their u-space boxes grown by R (1/z_min - 1/z_p), z_p the deepest
// receiver of a cell). Within a ring that lies in front of p, a chunk of eight edges beyond every edge
// shadow of p is one edge to the next chunk (EdgeChunk, stages.h: the same fan area).
//
// Parameters: grid (cells per side of the binning grid).
#include <algorithm>
#include <array>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/silhouette.h"
#include "rt/ray_scene.h"
#include "rt/shadow_ray.h"
#include "techniques/silhouette/convex_parts.h"
#include "techniques/silhouette/stages.h"

namespace penumbra {
namespace {

using namespace silhouette;

struct WedgeRing {
  uint32_t first = 0, count = 0;  //!< its vertices in order: Side::vertices[first, first + count), light space
  int32_t objectId = 0;
  uint32_t occluder = 0;  //!< index of its occluder
  uint8_t layer = 0;      //!< 0: solids; shells: 1 the front sides, 2 the back sides
  bool sheet = false;
  Vec2 uLower{kInfinity}, uUpper{-kInfinity};  //!< u-space box of the ring's part in front of the light
  float zMin = kInfinity;                      //!< its smallest depth there
  float zMax = -kInfinity;                     //!< its vertices' largest depth
  bool crossesNear = false;                    //!< some vertex lies nearer than zNear (behind this face of the light)
  uint32_t firstChunk = 0;                     //!< its chunks of edges in Side::chunks (set where !crossesNear)
};

// One face of the light: its light space and the silhouette seen from its centre.
struct Side {
  LightPlane plane;
  LightSectors sectors;  //!< the fan area of an edge whose projection passes outside the light
  std::vector<Vec3> vertices;
  std::vector<EdgeChunk> chunks;
  std::vector<WedgeRing> rings;
  UGrid grid;
  bool binned = false;
};

class WedgesTechnique final : public ShadowTechnique {
 public:
  // `occluders`: shared by the instances that run the parts of one concave light (convex_parts.h).
  WedgesTechnique(const WedgesOptions& options, std::shared_ptr<OccluderCache> occluders)
      : grid_(options.grid), occluderCache_(std::move(occluders)) {}
  std::string_view name() const override { return "wedges"; }

 private:
  void prepareImpl(const Scene& scene, const Light& light) override {
    prepared_ = false;
    const Bounds3 bounds = scene.bounds();
    zNear_ = 1e-4f * std::max(bounds.radius(), 1e-6f);
    edges_ = 0;
    for (int back = 0; back < 2; ++back) {
      sides_[back] = Side{};
      sides_[back].plane = makeLightPlane(light, bounds, "wedges", back == 1);
      sides_[back].sectors.build(sides_[back].plane.vertices);
    }
    occluders_ = &occluderCache_->get(scene);  // made again only when the geometry changed
    rays_ = nullptr;
    rays_ = &raysCache_.get(scene);  // built when the geometry changed, else kept
    light_ = light;
    epsilon_ = shadowRayEpsilon(bounds);
    // The other face of the light is built when a receiver lies behind the light's plane.
    buildSide(sides_[0]);
    backBuilt_ = false;
    prepared_ = true;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (!prepared_) fail("wedges: visibility() called before prepare(); call prepare(scene, light) first");
    const int width = gbuffer.width(), height = gbuffer.height();
    resetInParallel(v, width, height, 1.0f);
    if (!backBuilt_ && anyReceiverBehind(gbuffer, sides_[0].plane)) {
      buildSide(sides_[1]);
      backBuilt_ = true;
      endPass("back face silhouette");
    }
    for (Side& side : sides_) {
      Vec2 lower, upper;
      side.binned = !side.rings.empty() && receiverRange(gbuffer, side.plane, zNear_, lower, upper);
      if (!side.binned) continue;
      std::vector<Vec2> lo, hi;
      std::vector<float> near;
      for (const WedgeRing& r : side.rings) {
        lo.push_back(r.uLower);
        hi.push_back(r.uUpper);
        near.push_back(side.plane.extent / r.zMin);
      }
      // A ring's region of influence: its hard shadow (its box) and its edges' penumbrae (stages.h).
      side.grid.buildInfluence(lower, upper, grid_, lo, hi, near,
                               receiverCellFar(gbuffer, side.plane, zNear_, lower, upper, grid_), {});
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
      std::vector<Vec3> clipped, tmp;
      for (int y = range.begin(); y < range.end(); ++y)
        for (int x = 0; x < width; ++x) {
          if (!gbuffer.hit(x, y)) continue;
          const Vec3 wsP = gbuffer.wsPosition(x, y);
          // Receivers behind the light's plane see its other face.
          const Vec3 front = sides_[0].plane.lsFromWs(wsP);
          const Side& side = sides_[front.z > 0.0f ? 0 : 1];
          const Vec3 p = front.z > 0.0f ? front : side.plane.lsFromWs(wsP);
          // The object that hides the light's centre from p (kNoObject: none), traced once if needed.
          std::optional<int32_t> centreBlocker;
          auto blocker = [&]() {
            if (!centreBlocker) centreBlocker = silhouette::centreBlockerAt(*rays_, *light_, gbuffer, x, y, epsilon_);
            return *centreBlocker;
          };
          v(x, y) = visibilityAt(side, p, gbuffer.objectId(x, y), clipped, tmp, blocker);
        }
    });
  }

 public:
  std::vector<std::pair<std::string, double>> stats() const override {
    return {{"silhouette_edges", double(edges_)}, {"rings", double(sides_[0].rings.size())}};
  }

 private:
  void buildSide(Side& side) {
    const bool front = &side == &sides_[0];
    for (const Occluder& o : *occluders_) {
      const LightSpaceGeometry ls = toLightSpace(o, side.plane);
      const MeshTopology& m = o.topology;
      // Facets facing the light's centre (the origin of light space): the single silhouette.
      std::vector<uint8_t> facing(m.triangles.size());
      for (size_t t = 0; t < m.triangles.size(); ++t)
        facing[t] = glm::dot(ls.normals[t], -ls.positions[m.triangles[t].x]) > 0.0f;
      std::vector<uint8_t> shell(m.triangles.size(), 0);
      for (size_t i = 0; i < m.copyOf.size(); ++i) shell[m.copyOf[i]] = shell[m.surfaceTriangles + i] = 1;
      for (uint8_t layer = 0; layer < 3; ++layer) {
        std::vector<uint8_t> set(m.triangles.size());
        for (size_t t = 0; t < set.size(); ++t)
          set[t] = facing[t] && (layer == 0 ? !shell[t] : shell[t] && (layer == 1) == (t < m.surfaceTriangles));
        for (const auto& ringEdges : silhouetteRings(m, boundaryEdges(m, set))) {
          WedgeRing ring;
          ring.objectId = o.objectId;
          ring.occluder = static_cast<uint32_t>(&o - occluders_->data());
          ring.layer = layer;
          ring.sheet = o.sheet;
          ring.first = static_cast<uint32_t>(side.vertices.size());
          ring.count = static_cast<uint32_t>(ringEdges.size());
          for (const SilhouetteEdge& e : ringEdges) side.vertices.push_back(ls.positions[e.a]);
          for (uint32_t i = 0; i < ring.count; ++i) {
            Vec3 a = side.vertices[ring.first + i], b = side.vertices[ring.first + (i + 1) % ring.count];
            if (!clipToSlab(a, b, zNear_, kInfinity)) continue;
            for (const Vec3& q : {a, b}) {
              ring.zMin = std::min(ring.zMin, q.z);
              ring.uLower = glm::min(ring.uLower, Vec2(q.x / q.z, q.y / q.z));
              ring.uUpper = glm::max(ring.uUpper, Vec2(q.x / q.z, q.y / q.z));
            }
          }
          for (uint32_t i = 0; i < ring.count; ++i) {
            const float z = side.vertices[ring.first + i].z;
            ring.zMax = std::max(ring.zMax, z);
            ring.crossesNear = ring.crossesNear || !(z >= zNear_);
          }
          if (front) edges_ += ringEdges.size();
          if (ring.zMin == kInfinity) {  // entirely behind this face of the light
            side.vertices.resize(ring.first);
            continue;
          }
          ring.firstChunk = static_cast<uint32_t>(side.chunks.size());
          if (!ring.crossesNear)
            for (uint32_t i = 0; i < ring.count; i += kChunkEdges) {
              EdgeChunk c;
              for (uint32_t j = i; j <= std::min(i + kChunkEdges, ring.count); ++j) {  // the edges' both ends
                const Vec3& q = side.vertices[ring.first + j % ring.count];
                c.add(Vec2(q.x / q.z, q.y / q.z), q.z);
              }
              side.chunks.push_back(c);
            }
          side.rings.push_back(ring);
        }
      }
    }
  }

  template <typename Blocker>
  float visibilityAt(const Side& side, const Vec3& p, int32_t objectId, std::vector<Vec3>& clipped,
                     std::vector<Vec3>& tmp, Blocker& blocker) const {
    if (!side.binned || !(p.z > zNear_)) return 1.0f;
    const Vec2 u(p.x / p.z, p.y / p.z);
    const auto [begin, end] = side.grid.cell(u);
    const float zMax = p.z * (1.0f - 1e-4f);
    float total = 0.0f;
    // Per occluder: its solids' coverage plus the larger of its shells' front and back sides'.
    uint32_t current = 0xffffffffu;
    float layers[3] = {0.0f, 0.0f, 0.0f};
    auto flush = [&]() {
      total += layers[0] + std::max(layers[1], layers[2]);
      layers[0] = layers[1] = layers[2] = 0.0f;
    };
    for (const uint32_t* it = begin; it != end; ++it) {
      const WedgeRing& r = side.rings[*it];
      if (r.sheet && r.objectId == objectId) continue;
      // Whether the ring lies wholly within the depths zNear <= z <= zMax (uncut).
      const bool within = !r.crossesNear && r.zMax <= zMax;
      // A ring within the depths none of whose edges' wedges reach p covers nothing of the light:
      // all its edges project outside the light, winding around the centre zero times.
      if (within && beyondEdgeShadows(side.plane, r.uLower, r.uUpper, r.zMin, u, p.z)) continue;
      // The ring as a closed polygon clipped to zNear <= z <= zMax (Sutherland-Hodgman): where the
      // silhouette passes beyond p's depth (p on or beside the occluder), the cut is closed along
      // the plane just in front of p, whose projection runs far outside the light, as the part of
      // the loop "at infinity" seen from p would; clipping edge by edge would leave the loop open
      // and its winding undefined.
      // A ring wholly within the depths is used as it is, but for its chunks of edges beyond every
      // edge shadow of p: each is one edge to the next chunk (EdgeChunk, stages.h: the same fan area).
      const Vec3* ring = side.vertices.data() + r.first;
      size_t n = r.count;
      bool cut = false;
      if (within) {
        clipped.clear();
        bool passedOver = false;
        for (uint32_t i = 0, k = r.firstChunk; i < r.count; i += kChunkEdges, ++k) {
          if (side.chunks[k].beyond(side.plane, u, p.z)) {
            clipped.push_back(ring[i]);
            passedOver = true;
          } else {
            clipped.insert(clipped.end(), ring + i, ring + std::min(i + kChunkEdges, r.count));
          }
        }
        if (passedOver) {
          ring = clipped.data();
          n = clipped.size();
        }
      } else {
        clipped.assign(ring, ring + n);
        for (const float bound : {zNear_, zMax}) {
          const bool low = bound == zNear_;
          // A pass with every vertex within its bound leaves the ring as it is (the first keeps the
          // deepest vertex, deeper than zMax > zNear, and adds points at zNear only).
          if (low ? !r.crossesNear : r.zMax <= bound) continue;
          tmp.clear();
          const size_t count = clipped.size();
          for (size_t i = 0; i < count; ++i) {
            const Vec3 &a = clipped[i], &b = clipped[i + 1 < count ? i + 1 : 0];
            const bool inA = low ? a.z >= bound : a.z <= bound, inB = low ? b.z >= bound : b.z <= bound;
            if (inA) tmp.push_back(a);
            if (inA != inB) {
              const Vec3 c = a + (b - a) * ((bound - a.z) / (b.z - a.z));
              tmp.push_back(Vec3(c.x, c.y, bound));
              cut = true;
            }
          }
          clipped.swap(tmp);
        }
        ring = clipped.data();
        n = clipped.size();
      }
      if (n < 3) continue;  // also a ring of passed-over chunks left with fewer vertices: it winds around nothing
      float covered = 0.0f;
      int winding = 0;  // around the light's centre, the origin of the light plane
      if (!(side.sectors.valid() && ringFansBySectors(side.sectors, side.plane.vertices, p, ring, n, covered, winding)))
        ringFansByClipping(side.plane.vertices, p, ring, n, covered, winding);
      // covered = area * (the ring's hidden windings at the centre, -winding) + its wedge corrections.
      if (cut) covered += side.plane.area * (static_cast<float>(winding) + (blocker() == r.objectId ? 1.0f : 0.0f));
      if (r.occluder != current) {
        flush();
        current = r.occluder;
      }
      layers[r.layer] += covered;
    }
    flush();
    return 1.0f - std::clamp(total / side.plane.area, 0.0f, 1.0f);
  }

  int grid_;
  std::shared_ptr<OccluderCache> occluderCache_;
  const std::vector<Occluder>* occluders_ = nullptr;  //!< occluderCache_'s
  bool backBuilt_ = false;
  RaySceneCache raysCache_;
  const RayScene* rays_ = nullptr;  //!< the hard shadow of the light's centre
  std::optional<Light> light_;
  float epsilon_ = 0.0f;
  Side sides_[2];  //!< [0]: the face towards the scene's centre; [1]: the other face
  size_t edges_ = 0;
  float zNear_ = 0.0f;
  bool prepared_ = false;
};

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const WedgesOptions& o) {
  validateOptions("wedges", o);

  // A concave light runs as its convex parts, V combined by area (convex_parts.h).
  return overConvexParts("wedges", [o, occluders = std::make_shared<OccluderCache>()] {
    return std::make_unique<WedgesTechnique>(o, occluders);
  });
}

TechniqueInfo wedgesTechniqueInfo() {
  TechniqueInfo info;
  info.name = "wedges";
  info.summary =
      "penumbra wedges: one silhouette from the light's centre, exact per-edge light coverage, contributions added (a "
      "concave polygonal light in its fewest convex parts)";
  info.source = "baseline in Rouf 2007 (Assarsson & Akenine-Moeller 2003)";
  info.tracesRays = true;
  info.setOptions<WedgesOptions>([](const WedgesOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
