// The registry: the one list of techniques. Adding a technique = its own file defining
// `TechniqueInfo <name>TechniqueInfo()` plus one line here.
#include "penumbra/registry.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "penumbra/error.h"

namespace penumbra {

TechniqueInfo referenceTechniqueInfo();
TechniqueInfo noneTechniqueInfo();
TechniqueInfo raytracedHardTechniqueInfo();
TechniqueInfo raytracedSoftTechniqueInfo();
TechniqueInfo hybridTechniqueInfo();
TechniqueInfo hardTechniqueInfo();
TechniqueInfo pcfTechniqueInfo();
TechniqueInfo pcssTechniqueInfo();
TechniqueInfo multisampleTechniqueInfo();
TechniqueInfo brabecTechniqueInfo();
TechniqueInfo plmTechniqueInfo();
TechniqueInfo smoothiesTechniqueInfo();
TechniqueInfo kirschTechniqueInfo();
TechniqueInfo heidrichTechniqueInfo();
TechniqueInfo parkerTechniqueInfo();
TechniqueInfo ssvTechniqueInfo();
TechniqueInfo wedgesTechniqueInfo();

namespace {

// How each technique treats the light shapes, a concave polygon (an L-shaped window) above all: most
// single-sample techniques stand one point or one disk in for the light, and say which. Kept here,
// beside the list, so `penumbra techniques` shows them all in one place; a technique registered
// without a line fails tests/techniques/registry_test.cpp.
std::string lightHandling(const std::string& name) {
  static const std::vector<std::pair<std::string, std::string>> lines = {
      {"reference",
       "every shape, sampled over its emitting area; a concave polygon uniformly by area over its ear-clipping "
       "triangulation (unbiased)"},
      {"none", "every shape, a concave polygon too (ignored: V = 1)"},
      {"hard",
       "every shape, as a point at its centre sample; a polygon's is its area centroid, which for a concave one can "
       "lie off the emitter"},
      {"raytraced-hard",
       "every shape, as a point at its centre sample; a polygon's is its area centroid, which for a concave one can "
       "lie off the emitter"},
      {"raytraced-soft",
       "every shape, sampled over its emitting area (a concave polygon uniformly by area, so its shape is kept); the "
       "filter's width takes the light as a disk of radius Light::extent()"},
      {"hybrid",
       "every shape: rays sample its emitting area (a concave polygon uniformly by area); the map is taken from its "
       "centre sample and the blocker search takes it as a disk of radius Light::extent()"},
      {"pcf",
       "every shape, as a point at its centre sample (a concave polygon: its area centroid); the kernel does not "
       "follow the light's size"},
      {"pcss",
       "every shape; light_size defaults to Light::extent(), so a polygon, concave or not, is the disk around its "
       "centroid that holds it; a segment is a line of taps along its image in the map, a rect the parallelogram of "
       "its image"},
      {"multisample",
       "every shape, sampled over its emitting area; a concave polygon uniformly by area, so its shape is kept"},
      {"brabec",
       "every shape; r_max follows Light::extent(), so a polygon, concave or not, is the disk around its centroid that "
       "holds it"},
      {"plm",
       "sphere, disk, rect, polygon, directional; a polygon, concave or not, is the disk of equal area around its "
       "centroid; segment refused"},
      {"smoothies",
       "sphere, disk, rect, polygon, directional; a polygon, concave or not, is the disk of equal area around its "
       "centroid; segment refused"},
      {"kirsch",
       "sphere, disk, rect, polygon, directional; a polygon, concave or not, is the disk of equal area around its "
       "centroid; segment refused"},
      {"heidrich", "segment only; every other shape (a polygon too) is refused"},
      {"parker",
       "every shape but segment; a polygon, concave or not, is the sphere of its bounding diameter 2 Light::extent() "
       "around its centroid"},
      {"ssv",
       "rect and polygon (convex parts of at most 32 vertices); a concave polygon is cut into its fewest convex parts, "
       "run one by one, V combined by area (Rouf 2007, 5.2.5)"},
      {"wedges",
       "rect and polygon (convex parts of at most 32 vertices); a concave polygon is cut into its fewest convex parts, "
       "run one by one, V combined by area"},
  };
  for (const auto& [technique, line] : lines)
    if (technique == name) return line;
  return {};
}

// Bytes per texel of each light map, measured as the peak resident memory of `penumbra render` at
// map_size 4096 less that at 1024, divided by the texels added (tiny scene, 8 x 8 image).
constexpr double kDepthMapBytes = 8.0;        // hard, pcf, pcss: depth + object id
constexpr double kBrabecBytes = 9.0;          // depth + id + tile summaries and scratch
constexpr double kRibbonMapBytes = 60.0;      // plm: depth, limits, ribbons and their scratch
constexpr double kHalfRibbonMapBytes = 34.0;  // smoothies, kirsch: the hard map and one ribbon layer
constexpr double kHeidrichPointBytes = 40.0;  // per sample point: depth, id, two visibility layers, skins

ResourceEstimate mapEstimate(const Params& params, double maps, double bytesPerTexel, const std::string& extra = {}) {
  const auto size = static_cast<double>(params.getInt("map_size"));
  ResourceEstimate e;
  e.bytes = size * size * bytesPerTexel;
  e.texels = size * size * maps;
  e.drivers = fmt::format("map_size={}{}", params.getInt("map_size"), extra);
  return e;
}

// How much memory and work a run of technique `name` takes (ResourceEstimate); kept here, beside the
// list, like lightHandling, so every technique has one (registry_test.cpp checks it).
std::function<ResourceEstimate(const Params&, int, int)> resourceEstimate(const std::string& name) {
  using Estimate = std::function<ResourceEstimate(const Params&, int, int)>;
  const auto pixels = [](int w, int h) { return static_cast<double>(w) * static_cast<double>(h); };
  if (name == "reference")
    return Estimate([=](const Params& p, int w, int h) {
      return ResourceEstimate{0.0, pixels(w, h) * static_cast<double>(p.getInt("spp")), 0.0,
                              fmt::format("{} x {} pixels x spp={}", w, h, p.getInt("spp"))};
    });
  if (name == "raytraced-soft")
    return Estimate([=](const Params& p, int w, int h) {
      // Rays at most: a probe per 2 x 2 pixels, spp per pixel where every tile is a penumbra tile. Per
      // pixel the ray sums (16 bytes) and four images.
      return ResourceEstimate{pixels(w, h) * 32.0, pixels(w, h) * (static_cast<double>(p.getInt("spp")) + 0.25), 0.0,
                              fmt::format("at most {} x {} pixels x (spp={} + 1/4)", w, h, p.getInt("spp"))};
    });
  if (name == "hybrid")
    return Estimate([](const Params& p, int w, int h) {
      ResourceEstimate e = mapEstimate(p, 1.0, kDepthMapBytes);
      e.bytes += static_cast<double>(w) * h * 36.0;  // raytraced-soft's buffers and the search's ratio
      e.rays = static_cast<double>(w) * h * static_cast<double>(p.getInt("spp"));  // at most
      e.drivers += fmt::format(", at most {} x {} pixels x spp={}", w, h, p.getInt("spp"));
      return e;
    });
  if (name == "raytraced-hard" || name == "parker")
    return Estimate([=](const Params&, int w, int h) {
      return ResourceEstimate{0.0, pixels(w, h), 0.0, fmt::format("{} x {} pixels", w, h)};
    });
  if (name == "hard" || name == "pcf" || name == "pcss")
    return Estimate([](const Params& p, int, int) { return mapEstimate(p, 1.0, kDepthMapBytes); });
  if (name == "brabec") return Estimate([](const Params& p, int, int) { return mapEstimate(p, 1.0, kBrabecBytes); });
  if (name == "plm") return Estimate([](const Params& p, int, int) { return mapEstimate(p, 1.0, kRibbonMapBytes); });
  if (name == "smoothies" || name == "kirsch")
    return Estimate([](const Params& p, int, int) { return mapEstimate(p, 1.0, kHalfRibbonMapBytes); });
  if (name == "multisample")
    return Estimate([](const Params& p, int, int) {
      // Every sample's depth map is kept (4 bytes a texel) beside one full map being rendered.
      const auto samples = static_cast<double>(p.getInt("samples"));
      return mapEstimate(p, samples, 4.0 * samples + kDepthMapBytes, fmt::format(", samples={}", p.getInt("samples")));
    });
  if (name == "heidrich")
    return Estimate([](const Params& p, int, int) {
      const auto points = static_cast<double>(p.getInt("subdivisions") + 1);
      return mapEstimate(p, points, kHeidrichPointBytes * points,
                         fmt::format(", subdivisions={}", p.getInt("subdivisions")));
    });
  // none, ssv, wedges: buffers of the scene's size (edges, a light-space grid of at most 1024^2
  // cells), no light map, no rays.
  return Estimate([](const Params&, int, int) { return ResourceEstimate{}; });
}

}  // namespace

const std::vector<TechniqueInfo>& techniqueRegistry() {
  static const std::vector<TechniqueInfo> registry = [] {
    std::vector<TechniqueInfo> infos = {
        referenceTechniqueInfo(),
        noneTechniqueInfo(),
        hardTechniqueInfo(),
        raytracedHardTechniqueInfo(),
        pcfTechniqueInfo(),
        pcssTechniqueInfo(),
        multisampleTechniqueInfo(),
        brabecTechniqueInfo(),
        plmTechniqueInfo(),
        smoothiesTechniqueInfo(),
        kirschTechniqueInfo(),
        heidrichTechniqueInfo(),
        parkerTechniqueInfo(),
        ssvTechniqueInfo(),
        wedgesTechniqueInfo(),
        // Appended, not inserted: the fuzz corpus's seeds name a technique by its index here.
        raytracedSoftTechniqueInfo(),
        hybridTechniqueInfo(),
    };
    for (TechniqueInfo& info : infos) {
      info.lights = lightHandling(info.name);
      info.estimate = resourceEstimate(info.name);
    }
    return infos;
  }();
  return registry;
}

bool TechniqueInfo::hasParam(const std::string& param) const {
  for (const ParamSpec& p : params)
    if (p.name == param) return true;
  return false;
}

const TechniqueInfo& findTechnique(const std::string& name) {
  std::vector<std::string> names;
  for (const TechniqueInfo& info : techniqueRegistry()) {
    if (info.name == name) return info;
    names.push_back(info.name);
  }
  fail("unknown technique '{}' (known: {}; `penumbra techniques` lists them with their parameters)", name,
       fmt::join(names, ", "));
}

std::unique_ptr<ShadowTechnique> createTechnique(const std::string& name, const ParamSet& given) {
  const TechniqueInfo& info = findTechnique(name);
  return info.create(resolveParams(info.name, info.params, given));
}

}  // namespace penumbra
