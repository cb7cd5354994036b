// The silhouette family's shared stages (stages.cpp), used by `ssv` (ssv.cpp, Rouf 2007) and
// `wedges` (wedges.cpp, Assarsson & Akenine-Moeller 2003): the light's plane as a 2D polygon, the
// occluders' topologies, the central projection of occluder points from a receiver onto the light's
// plane, convex clipping, the binning grid, and the ray to the light's centre.
//
// Light space here: origin at the light's centre sample, z along Light::lightFrame's axis (towards
// the scene), x along the polygon's first edge (so a rect light's sides are the x and y axes, which
// the four quantized directions of Rouf Section 3.2.3.1 need), y = z x x. The light lies in z = 0.
//
// Binning (a light-space grid, chosen over a screen-space one because an edge's region of
// influence is a fixed shape in light space, independent of the camera): a receiver p is binned by
// its direction from the light's centre, u = (x/z, y/z). A point of an occluder edge at depth z_e can
// change the light's visibility from p only if p sees it in front of the light, and then
// |u_p - u_e| <= R (1/z_e - 1/z_p) < R / z_e, R the light's extent (the projection of the point from
// p onto the light's plane lies within R of the centre). So an edge's influence on the receivers of
// a cell lies in its u-space bounding box grown by R (1/min z_e - 1/z_c), z_c the deepest receiver
// of the cell (none if z_c <= min z_e): conservative, exact in the limit of a small light.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh_fingerprint.h"
#include "penumbra/gbuffer.h"
#include "penumbra/light.h"
#include "penumbra/scene.h"
#include "techniques/silhouette/mesh_topology.h"

namespace penumbra {
class RayScene;
}

namespace penumbra::silhouette {

inline constexpr int kMaxLightVertices = 32;

struct LightPlane {
  Vec3 wsOrigin{0.0f};
  Frame lsFrame;               //!< axes of light space in world space
  std::vector<Vec2> vertices;  //!< the polygon in light space (z = 0), counter-clockwise in (x, y)
  float area = 0.0f;
  float extent = 0.0f;            //!< R: the largest distance of a vertex from the centre
  Vec2 lower{0.0f}, upper{0.0f};  //!< bounding rectangle in (x, y)

  Vec3 lsFromWs(const Vec3& wsP) const { return lsFrame.toLocal(wsP - wsOrigin); }
  // min / max of dot(v, dir) over the light's vertices.
  void support(const Vec2& dir, float& lo, float& hi) const {
    lo = hi = glm::dot(vertices[0], dir);
    for (size_t i = 1; i < vertices.size(); ++i) {
      const float h = glm::dot(vertices[i], dir);
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
  }
};

// Rect and polygon lights (triangles, rects, thin rects, any convex polygon of at most
// kMaxLightVertices vertices); other shapes throw Error naming the shape and the supported ones, and
// so does a concave polygon (the techniques get its convex parts: convex_parts.h).
// Planar lights emit from both faces: `back` gives the light space of the other face (z reversed),
// for receivers behind the light's plane.
LightPlane makeLightPlane(const Light& light, const Bounds3& sceneBounds, std::string_view technique,
                          bool back = false);

struct Occluder {
  int32_t objectId = 0;
  std::string name;
  MeshTopology topology;  //!< world space
  bool sheet = false;     //!< a two-sided planar sheet (cannot shadow itself)
};

// An occluder's vertex positions and face normals in the light space of one face of the light.
struct LightSpaceGeometry {
  std::vector<Vec3> positions, normals;
};

// The scene's objects as occluders in world space: closed oriented surfaces (mesh_topology.h: a solid
// as given or repaired, any other mesh as a doubled shell; Rouf Section 1.3 asks for solids).
std::vector<Occluder> makeOccluders(const Scene& scene);
// The scene's occluders (makeOccluders), kept while every object's id, name and geometry (its mesh's
// fingerprint, core/mesh_fingerprint.h) stay the same: a light or camera moving over a static scene
// does not weld, pair and orient its meshes again every frame.
class OccluderCache {
 public:
  const std::vector<Occluder>& get(const Scene& scene);
  size_t builds() const { return builds_; }  //!< how many times the occluders were made

 private:
  struct Key {
    int32_t id = 0;
    std::string name;
    MeshFingerprint geometry;
    bool operator==(const Key&) const = default;
  };
  std::vector<Key> keys_;  //!< per object of the scene the occluders were made from
  std::vector<Occluder> occluders_;
  bool made_ = false;
  size_t builds_ = 0;
};

// The occluder's positions and normals in the light space of `plane`.
LightSpaceGeometry toLightSpace(const Occluder& o, const LightPlane& plane);

// Clips segment a-b to zMin <= z <= zMax; false if nothing is left.
inline bool clipToSlab(Vec3& a, Vec3& b, float zMin, float zMax) {
  if ((a.z < zMin && b.z < zMin) || (a.z > zMax && b.z > zMax)) return false;
  for (const float bound : {zMin, zMax}) {
    const bool lowSide = bound == zMin;
    const bool outA = lowSide ? a.z < bound : a.z > bound, outB = lowSide ? b.z < bound : b.z > bound;
    if (outA == outB) continue;
    const float s = (bound - a.z) / (b.z - a.z);
    const Vec3 c = a + (b - a) * s;
    (outA ? a : b) = Vec3(c.x, c.y, bound);
  }
  return true;
}

// The point where the line from receiver p through occluder point q meets the light's plane
// (z = 0); q must be nearer to the plane than p (q.z < p.z).
inline Vec2 projectFrom(const Vec3& p, const Vec3& q) {
  const float s = p.z / (p.z - q.z);
  return Vec2(p.x + (q.x - p.x) * s, p.y + (q.y - p.y) * s);
}

// Whether a receiver with direction u (from the light's centre) and depth z lies outside every edge
// shadow of an occluder part whose points' directions lie in [uLower, uUpper] at depths of at least
// zMin < z: a point e of it projects from the receiver into the light's bounding rectangle only
// where u_e - u = q (1 / z_e - 1 / z) for q in the rectangle (similar triangles), so u lies in the
// box grown by the rectangle times (1 / zMin - 1 / z); made a thousandth wider against rounding.
// Outside it u also lies outside the box: the part hides nothing of the light from the receiver.
inline bool beyondEdgeShadows(const LightPlane& plane, const Vec2& uLower, const Vec2& uUpper, float zMin,
                              const Vec2& u, float z) {
  const float k = 1.001f * (1.0f / zMin - 1.0f / z);
  const Vec2 lower = uLower - plane.upper * k, upper = uUpper - plane.lower * k;
  const Vec2 margin = 1e-6f * (glm::abs(lower) + glm::abs(upper));
  return u.x < lower.x - margin.x || u.y < lower.y - margin.y || u.x > upper.x + margin.x || u.y > upper.y + margin.y;
}

// kChunkEdges consecutive edges of a silhouette ring, with the box of their end points' directions
// from the light's centre and their least depth. A receiver beyond the edge shadows of a chunk
// (beyondEdgeShadows) sees all of it, projected, past one side of the light's bounding rectangle
// (the test bounds every point's projection there): in that half-plane, which holds neither the
// rectangle nor its centre, the chunk's projected path and the straight segment between its ends
// wind around no point of the rectangle, so the segment stands for the chunk in the ring's curve
// (ssv) or fan area (wedges). A pixel then projects one vertex instead of the chunk's; on a real mesh
// few of a ring's edges reach the light from any one pixel.
inline constexpr uint32_t kChunkEdges = 8;
struct EdgeChunk {
  Vec2 uLower{kInfinity}, uUpper{-kInfinity};
  float zMin = kInfinity;
  void add(const Vec2& u, float z) {
    uLower = glm::min(uLower, u);
    uUpper = glm::max(uUpper, u);
    zMin = std::min(zMin, z);
  }
  bool beyond(const LightPlane& plane, const Vec2& u, float z) const {
    return beyondEdgeShadows(plane, uLower, uUpper, zMin, u, z);
  }
};

// Clips the convex polygon in[0, count) to the half-plane dot(n, x) <= d (Sutherland-Hodgman) into
// `out` (room for count + 1 points); returns the number of points left.
int clipHalfPlane(const Vec2* in, int count, Vec2* out, const Vec2& n, float d);

// The light polygon's area by direction from its centre (the origin of light space), for penumbra
// wedges' fan areas (wedges.cpp). Where a segment a-b lies outside the polygon, the polygon's part
// inside the triangle (0, a, b) is its angular sector from a's direction to b's (a convex polygon
// around the origin ends, along every direction, before such a segment): sweep(b) - sweep(a), plus
// the polygon's area where the segment crosses the +x axis counter-clockwise (minus it where it
// crosses clockwise; the crossings the winding number counts, `crossingOfPositiveX`). Along a
// chain of such segments these sum to the chain's ends' sweeps and its crossings, without clipping.
// Where both ends of a segment lie inside the polygon, the triangle lies inside; only a segment that
// crosses the polygon's outline is left to clipping.
class LightSectors {
 public:
  // From the counter-clockwise polygon (at most 32 vertices); false (and nothing applies) unless the
  // origin lies strictly inside it.
  bool build(const std::vector<Vec2>& polygon);
  bool valid() const { return !polygon_.empty(); }
  float area() const { return area_; }
  // The edges of the polygon whose outer side q lies on (bit k: beyond edge k -> k + 1's line), every
  // bit where q is not finite. 0: q lies inside or on the boundary. Made once per projected vertex.
  uint32_t outcode(const Vec2& q) const {
    if (!(std::isfinite(q.x) && std::isfinite(q.y))) return ~0u;
    uint32_t code = 0;
    for (size_t k = 0; k < polygon_.size(); ++k) code |= glm::dot(outward_[k], q) > offset_[k] ? 1u << k : 0u;
    return code;
  }
  // Whether the segment a-b (finite; outcodes ca, cb) lies outside the polygon: beyond one edge's line
  // at both ends, or with the whole polygon on one side of its own line (the axes of the
  // separating-axis test of two convex shapes). With both outcodes 0 it lies inside: the triangle
  // (0, a, b) lies inside the polygon and its fan area is its own, cross(a, b) / 2.
  bool outside(const Vec2& a, const Vec2& b, uint32_t ca, uint32_t cb) const;
  // The polygon's area swept counter-clockwise from the +x axis to q's direction, in (0, area]: the
  // +x axis itself is swept whole, which matches crossingOfPositiveX's "a.y <= 0 is below". False
  // where q has no direction (zero).
  bool sweep(const Vec2& q, float& swept) const;

 private:
  std::vector<Vec2> polygon_, outward_;  //!< outward_[k]: the outward normal of edge k -> k + 1
  std::vector<float> offset_;            //!< dot(outward_[k], polygon_[k])
  std::vector<Vec2> outline_;            //!< the polygon from the point where the +x axis leaves it
  std::vector<float> coneArea_,
      prefix_;  //!< cone k: outline_[k]'s direction to outline_[k+1]'s; prefix_[k]: those before k
  float area_ = 0.0f;
};

// The z component of the cross product of a and b: twice the signed area of the triangle (0, a, b),
// positive where b lies counter-clockwise of a.
inline float cross2(const Vec2& a, const Vec2& b) { return a.x * b.y - a.y * b.x; }

// The signed crossing of segment a-b with the +x axis from the origin (the winding number's rule,
// Sunday 2001): +1 upward with the origin on its left, -1 downward with it on its right.
inline int crossingOfPositiveX(const Vec2& a, const Vec2& b) {
  const float side = cross2(a, b);
  if (a.y <= 0.0f) return (b.y > 0.0f && side > 0.0f) ? 1 : 0;
  return (b.y <= 0.0f && side < 0.0f) ? -1 : 0;
}

// Penumbra wedges' coverage of the light (wedges.cpp). The fan area of a projected edge a-b: the
// light's area inside the triangle (0, a, b), signed by the triangle's orientation, by clipping the
// (convex, counter-clockwise) light polygon to the triangle: exact for any convex light.
float clippedFanArea(const std::vector<Vec2>& light, const Vec2& a, const Vec2& b);
// A closed ring of n light-space points (nearer the light than p) projected from p: minus the sum of
// its edges' fan areas in `covered` (rings run counter-clockwise seen from the centre, clockwise in
// (x, y)) and its winding around the light's centre. Every fan area by clipping.
void ringFansByClipping(const std::vector<Vec2>& light, const Vec3& p, const Vec3* ring, size_t n, float& covered,
                        int& winding);
// The same, with most fan areas read off the light's sectors: an edge inside the light gives its own
// triangle; a chain of consecutive edges outside it gives its ends' sweeps and its crossings of the
// +x axis; only edges crossing the light's outline are clipped. False where a chain ends at a point
// without a direction (then ringFansByClipping applies).
bool ringFansBySectors(const LightSectors& sectors, const std::vector<Vec2>& light, const Vec3& p, const Vec3* ring,
                       size_t n, float& covered, int& winding);

// A uniform grid over a rectangle of u-space whose cells list the items whose boxes overlap them,
// in item order.
class UGrid {
 public:
  void build(const Vec2& lower, const Vec2& upper, int resolution, const std::vector<Vec2>& itemLower,
             const std::vector<Vec2>& itemUpper);
  // Regions of influence (the bound at the top of this file, per cell): an item at least `itemNear` = R / z_item deep
  // (z_item its smallest depth) can change the light's visibility only from receivers deeper than
  // it, and there within R (1/z_item - 1/z_p) of its box; a cell lists it when some receiver of
  // the cell can be such a receiver: cellFar[c] = R / (the deepest receiver in cell c), +infinity
  // for a cell without receivers. Items with equal consecutive `keys` are listed once per cell, as
  // their key (empty keys: the item's index).
  void buildInfluence(const Vec2& lower, const Vec2& upper, int resolution, const std::vector<Vec2>& itemLower,
                      const std::vector<Vec2>& itemUpper, const std::vector<float>& itemNear,
                      const std::vector<float>& cellFar, const std::vector<uint32_t>& keys);
  // The items of the cell holding u ([begin, end) into items()); empty outside the grid.
  std::pair<const uint32_t*, const uint32_t*> cell(const Vec2& u) const;
  // The cell holding u, or -1 outside the grid.
  int cellIndex(const Vec2& u) const;
  int resolution() const { return res_; }

 private:
  Vec2 lower_{0.0f}, scale_{0.0f};
  int res_ = 0;
  std::vector<uint32_t> start_, items_;
};

// Whether some G-buffer hit point lies behind the light's plane (z <= 0 in the light space of
// `plane`): only then is the light's other face needed.
bool anyReceiverBehind(const GBuffer& gbuffer, const LightPlane& plane);
// The u-space rectangle of the G-buffer's hit points in front of the light (z > zMin).
bool receiverRange(const GBuffer& gbuffer, const LightPlane& plane, float zMin, Vec2& lower, Vec2& upper);
// cellFar of UGrid::buildInfluence for a grid of `resolution` cells over [lower, upper]: R / the
// deepest receiver (z > zMin) in each cell, +infinity where there is none.
std::vector<float> receiverCellFar(const GBuffer& gbuffer, const LightPlane& plane, float zMin, const Vec2& lower,
                                   const Vec2& upper, int resolution);

// The object that hides the light's centre from G-buffer pixel (x, y) (kNoObject: none): one ray,
// offset and clipped as raytraced-hard's. ssv and wedges trace it only where their silhouettes
// cannot tell which side of their curves is hidden.
int32_t centreBlockerAt(const RayScene& rays, const Light& light, const GBuffer& gbuffer, int x, int y, float epsilon);
// The same towards the point wsLightPoint of the light (the origin offset as above).
int32_t blockerToward(const RayScene& rays, const Light& light, const GBuffer& gbuffer, int x, int y,
                      const Vec3& wsLightPoint, float epsilon);

}  // namespace penumbra::silhouette
