// `parker`: Parker, Shirley and Smits 1998, "Single Sample Soft Shadows" (University of Utah,
// 1998; docs/papers.md). One shadow ray per pixel to the light's centre; the
// shadow of a soft-edged object from a point light stands in for the soft shadow of the real object
// from the area light (Section 3, Figure 1):
//  - inner object = the object itself (Figure 2: anything smaller leaks light between touching
//    objects), tested with an Embree occlusion ray exactly as `raytraced-hard` (src/rt/shadow_ray.h:
//    same origin offset, same end short of the light), so parker is 0 exactly where that hard
//    shadow is 0 — except on analytic spheres, which are the true spheres their meshes are inscribed
//    in, so their umbra is a sliver larger;
//  - outer object = the object grown by b = D t0 / |l - o| (Appendix; t0 the distance along the ray
//    to the point nearest the occluder, D the light's diameter): a sphere of radius R + b for an
//    analytic sphere, the rounded triangles of the Appendix for meshes (src/techniques/parker/outer_objects.h);
//  - tau = (d - R) / b, s = 3 tau^2 - 2 tau^3 (the Bernstein form) or the exact sinusoid
//    (1 + sin(pi tau - pi/2)) / 2 (Section 3);
//  - every outer object the ray passes is seen (a hierarchy of bounds over the outer objects,
//    walked with the running minimum of tau: not only the first hit), combined by min (the paper's
//    choice), product or sum.
//
// Approximations (the paper's): the penumbra lies wholly outside the hard shadow and is as wide as
// the whole physical penumbra (Section 3: "the umbra region will be larger than in a physically-
// based computation"); the light is treated as a sphere of diameter D. Light shapes: sphere (D =
// 2 radius), disk, rect and polygon (D = their bounding diameter, 2 Light::extent(): the sphere that
// holds the emitter, as the paper's "roughly spherical lights" assumption needs one size), and
// directional (D = 2 tan(angular_diameter / 2), the solar disk's diameter at unit distance; b = D t0).
// The radiance profile (limb darkening) is not modelled. A segment light is rejected: its penumbra
// exists only along its length, which an outer object grown equally in every direction cannot give
// (use `heidrich`).
//
// Parameters: falloff (bernstein | sinusoid), combine (min | product | sum), analytic_spheres
// (bool), light_diameter (world units; directional: per unit distance; auto = as above).
//
// Cost (the paper: "approximately 20% slower" than hard ray-traced shadows). prepare builds the
// outer objects' hierarchy (the silhouettes depend on the light) and, beside it, the inner objects'
// BVH, which depends on the geometry alone: it is kept from the last prepare while the inner
// objects' positions and triangles are the same to the bit (a 128-bit fingerprint), so that a
// steady-state frame of a static scene under a moving light builds only the outer objects (stat
// inner_bvh_rebuilt); the meshes' edge adjacency, also light-independent, is kept alike, and only
// the silhouettes and the hierarchy are built again. visibility traces raytraced-hard's rays in packets of 16, one per
// 4 x 4 pixel tile, and the rays of a tile that miss every inner object walk the outer objects' hierarchy as one group.
// Numbers: bench/parker_bench.cpp.
#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/parker.h"
#include "rt/ray_scene.h"
#include "rt/shadow_packet.h"
#include "techniques/parker/outer_objects.h"

namespace penumbra {
namespace {

class ParkerTechnique final : public ShadowTechnique {
 public:
  explicit ParkerTechnique(const ParkerOptions& options) : options_(options) {}

  std::string_view name() const override { return "parker"; }

 private:
  void prepareImpl(const Scene& scene, const Light& light) override {
    if (light.shape() == LightShape::Segment)
      fail(
          "parker: a segment light is not supported (its penumbra runs only along the segment, which an outer object "
          "grown equally in every direction cannot give); supported: sphere, disk, rect, polygon, directional; use "
          "heidrich for a segment light");
    // The paper's D: the diameter of the (roughly spherical) light.
    const float diameter = options_.lightDiameter.value_or(2.0f * light.extent());
    rt::OuterObjectOptions outerOptions;
    outerOptions.lightDiameter = diameter;
    outerOptions.analyticSpheres = options_.analyticSpheres;

    // Inner objects: the meshes, except those whose analytic sphere the outer objects test.
    analyticIds_.clear();
    std::vector<const Object*> innerObjects;
    for (const Object& object : scene.objects) {
      if (!rt::OuterObjects::usesAnalyticSphere(object, outerOptions))
        innerObjects.push_back(&object);
      else
        analyticIds_.push_back(object.id);
    }
    std::sort(analyticIds_.begin(), analyticIds_.end());
    // The inner objects' BVH depends on the geometry alone, not on the light: kept from the last
    // prepare while the inner objects' positions and triangles are the same to the bit (a
    // steady-state frame of a static scene under a moving light builds only the outer objects;
    // their meshes' edge adjacency is kept alike, in edgeCache_).
    std::vector<rt::MeshFingerprint> key;
    key.reserve(innerObjects.size());
    for (const Object* object : innerObjects) key.push_back(rt::meshFingerprint(object->mesh));
    const bool rebuildInner = !rays_ || key != innerKey_;
    // The outer objects' hierarchy and the inner objects' BVH do not depend on each other: both
    // are built at once. An error of either is reported after both finish, the outer objects' first,
    // so the message does not depend on timing.
    std::exception_ptr outerError, innerError;
    const auto buildOuter = [&] {
      try {
        outer_ = std::make_unique<rt::OuterObjects>(scene, light, outerOptions, &edgeCache_);
      } catch (...) {
        outerError = std::current_exception();
      }
    };
    if (rebuildInner) {
      rays_.reset();
      tbb::parallel_invoke(buildOuter, [&] {
        try {
          Scene inner;
          inner.source = scene.source;
          for (const Object* object : innerObjects) inner.objects.push_back(*object);
          rays_ = std::make_unique<RayScene>(inner);
        } catch (...) {
          innerError = std::current_exception();
        }
      });
    } else {
      buildOuter();
    }
    if (outerError || innerError) {
      outer_.reset();
      rays_.reset();
      std::rethrow_exception(outerError ? outerError : innerError);
    }
    innerKey_ = std::move(key);
    innerRebuilt_ = rebuildInner;
    light_ = light;
    // The full scene's scale, as raytraced-hard and the reference use, so the rays are the same.
    epsilon_ = shadowRayEpsilon(scene.bounds());
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (!rays_ || !outer_ || !light_)
      fail("parker: visibility() called before prepare(); call prepare(scene, light) first");
    const int width = gbuffer.width(), height = gbuffer.height();
    resetInParallel(v, width, height, 1.0f);
    const Light& light = *light_;
    const rt::OuterObjects& outer = *outer_;
    const rt::OuterFalloff falloff = options_.falloff;
    const rt::OuterCombine combine = options_.combine;
    const bool directional = light.isDirectional();
    std::atomic<int64_t> rays{0};
    // 4 x 4 pixel tiles: one packet of occlusion rays each, and the rays that miss every inner
    // object walk the outer objects' hierarchy as one group (neighbouring rays share its bounds).
    constexpr int kTile = 4;
    static_assert(kTile * kTile == rt::OuterObjects::kGroup);
    const int tileRows = (height + kTile - 1) / kTile;
    tbb::parallel_for(tbb::blocked_range<int>(0, tileRows), [&](const tbb::blocked_range<int>& range) {
      rt::ShadowLanes lanes;
      RayPacket16 packet;
      Ray open[16];
      int xs[16], ys[16], openIndex[16];
      alignas(64) float facing[16];
      float toLight[16], s[16];
      rt::OuterObjects::Seeds seeds;  // the capsules of the last tile's minima, read first for the next
      int64_t rangeRays = 0;
      for (int tileRow = range.begin(); tileRow < range.end(); ++tileRow) {
        const int y0 = tileRow * kTile, y1 = std::min(height, y0 + kTile);
        for (int x0 = 0; x0 < width; x0 += kTile) {
          const int x1 = std::min(width, x0 + kTile);
          int count = 0;
          for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
              if (!gbuffer.hit(x, y)) continue;
              lanes.setSurface(count, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y));
              xs[count] = x;
              ys[count++] = y;
            }
          if (count == 0) continue;
          // raytraced-hard's rays to the light's centre, sixteen at a time (rt::buildCenterRays), and
          // the side each receiver faces.
          rt::buildCenterRays(light, lanes, count, epsilon_, packet, facing);
          if (!analyticIds_.empty()) {
            // A receiver on an analytic sphere's tessellation whose facet faces away from the light
            // is shadowed by its own closed surface, as raytraced-hard's ray through the facet finds
            // (near the terminator the true sphere would still face the light: the G-buffer, and the
            // reference, see the facets). Its lane leaves the packet.
            int kept = 0;
            for (int i = 0; i < count; ++i) {
              if (facing[i] < 0.0f &&
                  std::binary_search(analyticIds_.begin(), analyticIds_.end(), gbuffer.objectId(xs[i], ys[i]))) {
                v(xs[i], ys[i]) = 0.0f;
                continue;
              }
              packet.orgX[kept] = packet.orgX[i];
              packet.orgY[kept] = packet.orgY[i];
              packet.orgZ[kept] = packet.orgZ[i];
              packet.dirX[kept] = packet.dirX[i];
              packet.dirY[kept] = packet.dirY[i];
              packet.dirZ[kept] = packet.dirZ[i];
              packet.tMax[kept] = packet.tMax[i];
              xs[kept] = xs[i];
              ys[kept++] = ys[i];
            }
            count = kept;
            if (count == 0) continue;
          }
          rays_->occluded16(packet, count);
          rangeRays += count;
          int openCount = 0;
          for (int i = 0; i < count; ++i) {
            if (packet.blocked(i)) {
              v(xs[i], ys[i]) = 0.0f;  // the inner object: umbra
              continue;
            }
            // An open ray is in the packet as it was traced (the query overwrites a blocked ray's tMax only).
            Ray& ray = open[openCount];
            ray.origin = Vec3(packet.orgX[i], packet.orgY[i], packet.orgZ[i]);
            ray.direction = Vec3(packet.dirX[i], packet.dirY[i], packet.dirZ[i]);
            ray.tMin = 0.0f;
            ray.tMax = packet.tMax[i];
            // shadowRay stops epsilon short of the centre: the distance to the centre is tMax + epsilon.
            toLight[openCount] = directional ? kInfinity : ray.tMax + epsilon_;
            openIndex[openCount++] = i;
          }
          // The outer objects of the rays that miss every inner object, as one group.
          outer.attenuations(open, toLight, openCount, falloff, combine, s, &seeds);
          for (int k = 0; k < openCount; ++k) v(xs[openIndex[k]], ys[openIndex[k]]) = s[k];
        }
      }
      rays += rangeRays;
    });
    rayCount_ = static_cast<double>(rays.load());
  }

 public:
  std::vector<std::pair<std::string, double>> stats() const override {
    if (!outer_) return {};
    return {{"analytic_spheres", static_cast<double>(outer_->analyticSphereCount())},
            {"silhouette_edges", static_cast<double>(outer_->silhouetteEdgeCount())},
            {"outer_pieces", static_cast<double>(outer_->pieceCount())},
            {"outer_leaves", static_cast<double>(outer_->leafCount())},
            {"inner_bvh_rebuilt", innerRebuilt_ ? 1.0 : 0.0},
            {"rays", rayCount_}};
  }

 private:
  ParkerOptions options_;
  std::unique_ptr<rt::OuterObjects> outer_;
  std::unique_ptr<RayScene> rays_;
  std::optional<Light> light_;
  std::vector<int32_t> analyticIds_;           //!< ids of the objects whose analytic sphere is used, sorted
  std::vector<rt::MeshFingerprint> innerKey_;  //!< the inner objects' geometry rays_ was built from
  rt::OuterObjects::EdgeCache edgeCache_;      //!< the meshes' edge adjacency, kept while they stay the same
  bool innerRebuilt_ = false;                  //!< the last prepare built rays_ (else it kept it)
  float epsilon_ = 0.0f;
  double rayCount_ = 0.0;
};

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const ParkerOptions& o) {
  validateOptions("parker", o);
  return std::make_unique<ParkerTechnique>(o);
}

TechniqueInfo parkerTechniqueInfo() {
  TechniqueInfo info;
  info.name = "parker";
  info.usesMeshEdges = true;
  info.summary =
      "one shadow ray per pixel to the light's centre; soft-edged outer objects (R + b, b = D t0 / |l - o|) give the "
      "penumbra";
  info.source = "Parker, Shirley & Smits 1998, Single sample soft shadows";
  info.setOptions<ParkerOptions>([](const ParkerOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
