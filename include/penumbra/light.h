// Lights: the emitters of docs/architecture.md ("Lights"), with the operations every technique and the
// reference need — the centre sample, uniform stratified sampling of the emitting area as seen from
// a point, the light's size, and its unshadowed irradiance.
//
// Conventions (units are world units unless stated):
//  - sphere {center, radius}; its emitting area seen from p is the silhouette disk: the disk of
//    radius R*sqrt(d^2 - R^2)/d, at distance (d^2 - R^2)/d from p, perpendicular to p->center.
//  - disk {center, normal, radius}, rect {center, u, v} (u, v half-edge vectors, any lengths, must
//    be perpendicular), polygon {vertices} (>= 3, in order, either orientation; planar and simple:
//    no two vertices coincide and no two edges cross or touch; convex or concave): planar emitters
//    that emit from both faces, so a ceiling light works whichever way its normal points. A
//    polygon's centre sample is its area centroid, which for a concave polygon (an L, a U) can lie
//    off the emitter; it is sampled uniformly by area over a triangulation (a fan from vertex 0 when
//    convex, ear clipping otherwise).
//  - segment {a, b}: a linear light (Heidrich et al. 2000); sampled uniformly along its length.
//  - directional {direction, angular_diameter, profile}: `direction` points from the scene towards
//    the light (the sun direction); its emitting area is the solar disk, a disk of radius
//    tan(angular_diameter / 2) at unit distance perpendicular to `direction`, sampled uniformly in
//    area, so the visible fraction behind a straight edge is exactly a circular-segment area.
//    The limb-darkened profile weights a point at normalized disk radius rho by the linear law
//    I(mu) / I(1) = 1 - u (1 - mu), mu = sqrt(1 - rho^2), u = 0.6 (the Sun near 550 nm).
//  - intensity: emitted radiance for area lights, radiant intensity per unit length for a
//    segment, and irradiance at normal incidence for a directional light. It only scales shading;
//    visibility V does not depend on it.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "penumbra/math.h"

namespace penumbra {

enum class LightShape { Sphere, Disk, Rect, Segment, Polygon, Directional };
enum class LightProfile { Uniform, LimbDarkened };

std::string_view toString(LightShape shape);
std::string_view toString(LightProfile profile);

// Linear limb-darkening coefficient of the directional light's limb-darkened profile.
inline constexpr float kLimbDarkeningU = 0.6f;

// One sample of the emitting area, as seen from a shaded point p.
struct LightSample {
  Vec3 wsDirection;  //!< unit vector from p towards the sample
  float distance;    //!< from p to the sample; kInfinity for a directional light
  float weight;      //!< radiance-profile weight, mean 1 over the emitting area (1 when uniform)
};

// What of a sample (Light::sample) depends on u alone, for a pattern of u used from many points: the
// point on the emitter (disk, rect, segment, polygon), the unscaled concentric-disk point (sphere) or
// the whole sample (directional). Light::sampleFrom(p, light.patternPoint(u)) is sample(p, u) to the bit.
struct LightPatternPoint {
  Vec3 onLight{0.0f};  //!< the emitter's point; a directional light's direction
  Vec2 disk{0.0f};     //!< a sphere's concentric-disk point of u
  float weight = 1.0f;
};

class Light {
 public:
  // Factories validate their input and throw Error for a degenerate light (zero or non-finite
  // size, a non-planar or self-intersecting polygon or one with repeated vertices, parallel rect
  // edges, ...).
  static Light sphere(const Vec3& center, float radius);
  static Light disk(const Vec3& center, const Vec3& normal, float radius);
  static Light rect(const Vec3& center, const Vec3& u, const Vec3& v);
  static Light segment(const Vec3& a, const Vec3& b);
  static Light polygon(const std::vector<Vec3>& vertices);
  static Light directional(const Vec3& wsToLight, float angularDiameterRadians,
                           LightProfile profile = LightProfile::Uniform);

  LightShape shape() const { return shape_; }
  bool isDirectional() const { return shape_ == LightShape::Directional; }
  LightProfile profile() const { return profile_; }
  float intensity() const { return intensity_; }
  void setIntensity(float intensity);  // >= 0, finite

  // The centre sample: the point a single-sample technique treats as a point light.
  Vec3 center() const { return center_; }
  // Unit direction from p towards the centre sample, and the distance to it (kInfinity when directional).
  Vec3 directionToCenter(const Vec3& wsP) const;
  float distanceToCenter(const Vec3& wsP) const;

  // Shape parameters (meaningful for the shapes that have them).
  float radius() const { return radius_; }                    //!< sphere, disk
  Vec3 normal() const { return normal_; }                     //!< disk, rect, polygon: unit plane normal
  Vec3 u() const { return u_; }                               //!< rect half-edge
  Vec3 v() const { return v_; }                               //!< rect half-edge
  Vec3 a() const { return a_; }                               //!< segment end
  Vec3 b() const { return b_; }                               //!< segment end
  Vec3 direction() const { return direction_; }               //!< directional: unit, scene -> light
  float angularDiameter() const { return angularDiameter_; }  //!< directional, radians
  // Corners of rect and polygon lights, in order (for rect: c-u-v, c+u-v, c+u+v, c-u+v).
  const std::vector<Vec3>& vertices() const { return vertices_; }
  // Emitting area of disk, rect and polygon lights (world units squared); 0 for the other shapes.
  float area() const;
  // Rect and polygon lights: whether the polygon is convex (every corner turns the same way, to a
  // tolerance of 1e-6 of its squared size). False for the other shapes.
  bool convex() const { return convex_; }
  // Rect and polygon lights: convex polygons (in the light's own orientation, straight corners
  // dropped) that tile it without overlap: the polygon itself when convex, otherwise the fewest
  // pieces cut along diagonals and edge extensions, the shortest cuts among those (an L gives two
  // rectangles; planar_polygon.h's convexPartition; Rouf 2007, Section 5.2.5). Empty for the other
  // shapes.
  std::vector<std::vector<Vec3>> convexParts() const;

  // Radius of the smallest circle around the centre that holds the emitter (world units); for a
  // directional light, tan(angular_diameter / 2), the solar disk's radius at unit distance.
  float extent() const;
  // Angular radius (radians) of that circle as seen from p: the light's size as seen from a point.
  float apparentRadius(const Vec3& wsP) const;

  // A point of the emitting area for u in [0,1)^2, as seen from p (see the conventions above).
  // For a segment only u.x is used. Stratified u gives stratified samples.
  LightSample sample(const Vec3& wsP, const Vec2& u) const;
  // sample() in two halves, for a fixed pattern of u seen from many points (the half that depends on u
  // alone made once per u): sampleFrom(p, patternPoint(u)) == sample(p, u), bit for bit.
  LightPatternPoint patternPoint(const Vec2& u) const;
  LightSample sampleFrom(const Vec3& wsP, const LightPatternPoint& point) const;

  // Unshadowed irradiance at p with unit normal n (only for shading; never for V).
  float irradiance(const Vec3& wsP, const Vec3& wsN) const;

  // Light space (docs/architecture.md, "Spaces"): origin at the centre sample, +z along the light's
  // axis towards the scene. Planar lights use their normal (flipped to face the scene); spheres and
  // segments point at the scene's centre; a directional light's +z is -direction. x and y complete a
  // right-handed frame.
  Frame lightFrame(const Bounds3& sceneBounds) const;

 private:
  Light() = default;

  LightShape shape_ = LightShape::Sphere;
  LightProfile profile_ = LightProfile::Uniform;
  float intensity_ = 1.0f;
  Vec3 center_{0.0f};
  float radius_ = 0.0f;
  Vec3 normal_{0.0f, 0.0f, 1.0f};
  Vec3 u_{0.0f}, v_{0.0f};
  Vec3 a_{0.0f}, b_{0.0f};
  Vec3 direction_{0.0f, 1.0f, 0.0f};
  float angularDiameter_ = 0.0f;
  std::vector<Vec3> vertices_;
  bool convex_ = false;
  std::vector<std::array<uint32_t, 3>> triangles_;  // polygon: a triangulation (vertex indices)
  std::vector<float> triangleCdf_;                  // polygon: cumulative triangle areas, normalized
};

}  // namespace penumbra
