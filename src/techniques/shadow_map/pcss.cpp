// `pcss`: percentage-closer soft shadows (Fernando 2005, "Percentage-closer soft shadows",
// SIGGRAPH sketch; NVIDIA whitepaper of the same name). One shadow map from the light's centre, then
// per camera pixel three steps:
//  1. blocker search: the mean depth z_b of the map texels in front of the receiver inside the
//     region through which the receiver sees the light — by similar triangles, a light of radius
//     R at depth 0 seen from a receiver at depth z_r covers, at depth z, a disk of radius
//     R (z_r - z) / z_r, which projects into the map (from the centre) with radius
//     R (z_r - z) / (z_r z) at unit depth; taken at the nearest depth in the map (z = zMin, found in
//     prepare(); the sketch uses the near plane, which only wastes samples);
//  2. penumbra estimate: a planar blocker at z_b parallel to the light blurs the shadow by the
//     light's projection through it, a disk of radius w = R (z_r - z_b) / z_b on the receiver's
//     plane (the sketch's w_penumbra = (d_receiver - d_blocker) w_light / d_blocker);
//  3. PCF over that disk: `filter_samples` taps, each a 1-texel box compare (bilinear weights) while
//     the disk's radius is at most `bilinear_max_radius` texels, so narrow penumbrae stay
//     antialiased; wider disks take one nearest-texel compare per tap (a quarter of the reads; their
//     taps lie over a texel apart, where the box smooths little).
// Both disks use Vogel's spiral (deterministic; the sketch uses a Poisson disk), rotated per pixel
// when `rotate` is on (banding becomes fine noise) by one of 256 angles read from a 16x16 tile
// (PixelRotations: a table read, where a hash per pixel cost a few percent of the frame).
//
// The kernels are vectorized (shadow_map.cpp: an AVX2 clone picked at load time, and 16 taps per
// 512-bit vector with one gather each where the CPU has AVX-512F), V bit-identical on every path,
// and run a row of pixels per call (the searches, then each filter's pixels), so that what does not
// depend on the pixel is done once a row; lit pixels and umbra are decided by the search alone. No
// early-out skips the search: a receiver tilted towards the light sweeps more depth over a search
// region than the bias allows, so bounds of the map per region or tile rarely decide a pixel, and the
// 16-tap search costs less than a few tile tests.
// Directional lights use the orthographic variant: R is tan(angular_diameter / 2), the solar disk's
// radius at unit distance, and the radii are R (z_r - z) and R (z_r - z_b) in world units (no
// perspective division).
//
// Approximations (the sketch's): the blockers are replaced by one plane at their mean depth (so
// overlapping occluders at different depths get one penumbra width); the light is a disk of radius
// `light_size` facing the receivers — by default Light::extent(), the radius of the circle holding
// the emitter (exact for sphere and disk lights, the circumscribed disk of a polygon). Segment and
// rect lights keep their own shape, as the sketch's similar triangles hold for any light shape
// (through a blocker point the receiver sees the light's outline, point-reflected and scaled): a
// segment's taps lie evenly along the segment's image in the map (the direction of its light-space
// x-y part; radius by default that part's length, half the segment foreshortened as the map sees
// it), so its shadow blurs along the segment only and stays as sharp as a point light's across it;
// a rect's taps cover the parallelogram of its light-space x-y half-edges (radius by default the
// larger of its half-diagonals there), where the circumscribed disk would blur a segment's shadow
// across it and a rect's up to sqrt(2) too wide. Neither pattern turns per pixel (`rotate` is for
// the disks). The map is taken from the centre sample, so blockers hidden behind others from the
// centre are missed. Receiver-plane compare and bias as in shadow_map.h.
#include <algorithm>
#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/shadow_map.h"
#include "shadow_map.h"

namespace penumbra {

class PcssTechnique final : public ShadowTechnique {
 public:
  explicit PcssTechnique(const PcssOptions& options)
      : options_(options),
        blockerDisk_(vogelDisk(options.blockerSamples)),
        filterDisk_(vogelDisk(options.filterSamples)),
        blockerLine_(linePattern(options.blockerSamples)),
        filterLine_(linePattern(options.filterSamples)) {}

  std::string_view name() const override { return "pcss"; }

 private:
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestDepth;  // compares depths only

  void reserveImpl(int, int) override { reserveShadowMap(options_.lightMap, map_, kLayers); }

  void prepareImpl(const Scene& scene, const Light& light) override {
    lightSize_ = options_.lightSize ? *options_.lightSize : light.extent();
    createShadowMap(scene, light, options_.lightMap, map_, kLayers);
    setHorizonClamp(options_.lightMap.horizon, lightAtMapOrigin(light, map_));
    // Segment and rect lights: the taps lie on the light's own image in the map (see the file
    // comment), not on the disk that circumscribes it.
    lineDirection_.reset();
    rectPatterns_ = false;
    if (light.shape() == LightShape::Segment) {
      const Vec3 lsU = map_.lsFrame.toLocal(0.5f * (light.b() - light.a()));
      const Vec2 across(lsU.x, -lsU.y);  // map s grows with light-space x, t falls with y
      const float length = glm::length(across);
      if (length > 0.0f) {
        lineDirection_ = across / length;
        if (!options_.lightSize) lightSize_ = length;
      }
    } else if (light.shape() == LightShape::Rect) {
      const Vec3 lsU = map_.lsFrame.toLocal(light.u()), lsV = map_.lsFrame.toLocal(light.v());
      const Vec2 U(lsU.x, -lsU.y), V(lsV.x, -lsV.y);
      const float radius = std::max(glm::length(U + V), glm::length(U - V));
      if (radius > 0.0f) {
        rectPatterns_ = true;
        if (!options_.lightSize) lightSize_ = radius;
        blockerRect_ = rectPattern(options_.blockerSamples, U / radius, V / radius);
        filterRect_ = rectPattern(options_.filterSamples, U / radius, V / radius);
      }
    }
    zMin_ = minMapDepth(map_);
    // The search radius's factors that do not depend on the pixel (one division per pixel fewer).
    searchScale_ = map_.orthographic ? lightSize_ : lightSize_ / zMin_;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("pcss: visibility() called before prepare()");
    const int width = gbuffer.width();
    v.resizeForOverwrite(width, gbuffer.height());  // every pixel written below, in parallel
    std::array<std::atomic<int64_t>, kPathCount + 1> counts{};
    // A row at a time: the receivers set up (forEachReceiverRow), then the blocker searches of the
    // row's pixels in one call (the work that does not depend on the pixel done once), then each
    // pixel's filter; per-row counts of the paths the pixels took.
    tbb::enumerable_thread_specific<RowScratch> scratch;
    const HorizonBound horizon = horizonForRows();
    forEachReceiverRow(gbuffer, map_, options_.bias, [&](int y, const ReceiverRow& receivers) {
      RowScratch& w = scratch.local();
      w.resize(static_cast<size_t>(width));
      std::array<int64_t, kPathCount + 1> local{};
      float* out = v.row(y);
      // The pixels that search and their radii, the whole row in one vectorized pass: the set-up runs
      // for every pixel, so it takes no branch and no scalar division per pixel.
      const SearchingPixels searching =
          listSearchingPixels(gbuffer.objectId.row(y), receivers, width, searchScale_, zMin_, maxRadius(),
                              w.pixelList.data(), w.radius.data(), w.searchClamped.data(), out);
      const std::span<const int32_t> pixels(w.pixelList.data(), static_cast<size_t>(searching.count));
      local[kNoSearch] = searching.hits - searching.count;
      local[kClamped] = searching.clamped;
      setRotations(y, pixels, w.rotation.data());
      searchBlockersRow(depthTexels(map_), receivers, pixels, w.radius.data(), w.rotation.data(), blockerPattern(),
                        w.blockers.data());
      // The search decides a pixel where it finds no blocker (lit) or only blockers (umbra: the filter
      // disk lies inside the search disk, as z_b >= zMin makes w <= the search radius, so filtering
      // would find (nearly) only blockers too; skipping it halves the cost of PCSS in shadowed
      // regions, as NVIDIA's PCSS sample does). V is written for every searched pixel without a
      // branch and the undecided ones are kept, in place, for the filters.
      const int taps = static_cast<int>(blockerPattern().size());
      size_t undecided = 0;
      for (const int32_t x : pixels) {
        const int found = w.blockers[static_cast<size_t>(x)].blockers;
        out[x] = found == 0 ? 1.0f : 0.0f;
        w.pixelList[undecided] = x;  // undecided <= the index read: the list is compacted in place
        undecided += found != 0 && found != taps;
      }
      local[kSearchOnly] = static_cast<int64_t>(pixels.size() - undecided);
      // Then each filter's pixels in one call.
      w.bilinear.clear();
      w.nearest.clear();
      for (const int32_t x : std::span<const int32_t>(w.pixelList.data(), undecided)) {
        const auto i = static_cast<size_t>(x);
        const float filterRadius = filterRadiusOf(receivers[x], w.blockers[i], !w.searchClamped[i], local);
        w.radius[i] = filterRadius;
        (filterRadius <= options_.bilinearMaxRadius ? w.bilinear : w.nearest).push_back(x);
      }
      local[kFilterBilinear] += static_cast<int64_t>(w.bilinear.size());
      local[kFilterNearest] += static_cast<int64_t>(w.nearest.size());
      const DepthTexels texels = depthTexels(map_);
      pcfDiskRow(texels, receivers, w.bilinear, w.radius.data(), w.rotation.data(), filterPattern(), out);
      pcfDiskNearestRow(texels, receivers, w.nearest, w.radius.data(), w.rotation.data(), filterPattern(), out);
      clampRowToHorizon(gbuffer, horizon, y, out);
      for (size_t k = 0; k <= kPathCount; ++k) counts[k] += local[k];
    });
    int64_t total = 0;
    for (size_t k = 0; k < kPathCount; ++k) total += counts[k];
    for (size_t k = 0; k <= kPathCount; ++k)
      pathFractions_[k] = total > 0 ? static_cast<double>(counts[k]) / static_cast<double>(total) : 0.0;
  }

 public:
  std::vector<std::pair<std::string, double>> stats() const override {
    std::vector<std::pair<std::string, double>> s = {{"light_size", lightSize_}, {"min_map_depth", zMin_}};
    for (size_t k = 0; k <= kPathCount; ++k) s.emplace_back(kPathNames[k], pathFractions_[k]);
    return s;
  }

 private:
  // Where a pixel's V was decided, reported as fractions of the receiver pixels (stats()).
  // kClamped counts, beside the paths, the pixels whose search or filter radius was clamped to the map.
  enum Path : size_t { kNoSearch, kSearchOnly, kFilterBilinear, kFilterNearest, kPathCount, kClamped = kPathCount };
  static constexpr std::array<const char*, kPathCount + 1> kPathNames = {
      "frac_no_search", "frac_search_only", "frac_filter_bilinear", "frac_filter_nearest", "frac_clamped_to_map"};

  // A row's working arrays, kept per thread.
  struct RowScratch {
    std::vector<int32_t> pixelList;          //!< the pixels that search, then (in place) those left undecided
    std::vector<int32_t> bilinear, nearest;  //!< those that filter, by filter
    std::vector<float> radius;               //!< per pixel: the search's radius, then the filter's, texels
    std::vector<uint8_t> searchClamped;      //!< per pixel: the search's radius was cut to the map's size
    std::vector<Vec2> rotation;              //!< per pixel: the patterns' rotation
    std::vector<BlockerSearch> blockers;
    void resize(size_t n) {
      radius.resize(n);
      searchClamped.resize(n);
      rotation.resize(n);
      blockers.resize(n);
      pixelList.resize(n);
      bilinear.reserve(n);
      nearest.reserve(n);
    }
  };

  // A search wider than the map finds nothing more.
  float maxRadius() const { return static_cast<float>(map_.size); }
  // The disks turn per pixel; a segment's line and a rect's pattern keep the light's orientation.
  Vec2 rotation(int x, int y) const {
    return lineDirection_ ? *lineDirection_ : !rectPatterns_ && options_.rotate ? rotations_(x, y) : Vec2(1.0f, 0.0f);
  }
  void setRotations(int y, std::span<const int32_t> pixels, Vec2* rotations) const {
    for (const int32_t x : pixels) rotations[x] = rotation(x, y);
  }
  const std::vector<Vec2>& blockerPattern() const {
    return lineDirection_ ? blockerLine_ : rectPatterns_ ? blockerRect_ : blockerDisk_;
  }
  const std::vector<Vec2>& filterPattern() const {
    return lineDirection_ ? filterLine_ : rectPatterns_ ? filterRect_ : filterDisk_;
  }

  // The filter's radius in texels for a receiver and its blocker search, which found some blockers and
  // some lit taps (searchUnclamped: the search's radius was within the map).
  float filterRadiusOf(const ShadowReceiver& r, const BlockerSearch& blockers, bool searchUnclamped,
                       std::array<int64_t, kPathCount + 1>& counts) const {
    const float zr = r.lsDepth;
    const float zb = blockers.meanDepth;
    const float penumbraWorld = map_.orthographic ? lightSize_ * (zr - zb) : lightSize_ * (zr - zb) / zb;
    // The receiver plane's slope extrapolated across a wide search can count texels behind the
    // receiver's own depth as blockers, putting z_b past z_r: a negative (or NaN) width is no
    // penumbra, and a filter radius outside [0, map size] would read outside the map.
    const float widthTexels = penumbraWorld / r.texelWorld;
    counts[kClamped] += widthTexels > maxRadius() && searchUnclamped;
    return widthTexels > 0.0f ? std::min(widthTexels, maxRadius()) : 0.0f;
  }

  // n offsets evenly spread over [-1, 1] x {0}, the midpoints of n equal pieces (a segment light's
  // taps, turned onto its image in the map).
  static std::vector<Vec2> linePattern(int n) {
    std::vector<Vec2> pattern(static_cast<size_t>(std::max(n, 0)));
    for (int i = 0; i < n; ++i)
      pattern[static_cast<size_t>(i)] =
          Vec2((2.0f * static_cast<float>(i) + 1.0f) / static_cast<float>(n) - 1.0f, 0.0f);
    return pattern;
  }

  // n offsets a U + b V spread over the parallelogram of half-edges U, V (a rect light's image in
  // the map, scaled to its circumscribed radius): (a, b) on a Fibonacci lattice of [-1, 1]^2, a the
  // midpoints of n equal pieces and b stepping by the golden ratio, so every row and column of the
  // rect is sampled evenly.
  static std::vector<Vec2> rectPattern(int n, const Vec2& U, const Vec2& V) {
    std::vector<Vec2> pattern(static_cast<size_t>(std::max(n, 0)));
    for (int i = 0; i < n; ++i) {
      const float a = 2.0f * (static_cast<float>(i) + 0.5f) / static_cast<float>(n) - 1.0f;
      const float g = static_cast<float>(i) * 0.6180339887f + 0.5f;
      const float b = 2.0f * (g - std::floor(g)) - 1.0f;
      pattern[static_cast<size_t>(i)] = a * U + b * V;
    }
    return pattern;
  }
  PcssOptions options_;
  std::vector<Vec2> blockerDisk_, filterDisk_, blockerLine_, filterLine_;
  std::optional<Vec2> lineDirection_;  //!< segment lights: the unit direction of the segment's image in the map
  bool rectPatterns_ = false;          //!< rect lights: blockerRect_ and filterRect_ replace the disks
  std::vector<Vec2> blockerRect_, filterRect_;
  PixelRotations rotations_;
  LightMap map_;
  float lightSize_ = 0.0f;
  float zMin_ = 0.0f;
  float searchScale_ = 0.0f;  //!< lightSize_ (orthographic) or lightSize_ / zMin_ (perspective)
  std::array<double, kPathCount + 1> pathFractions_{};
};

std::unique_ptr<ShadowTechnique> makeTechnique(const PcssOptions& o) {
  validateOptions("pcss", o);
  return std::make_unique<PcssTechnique>(o);
}

TechniqueInfo pcssTechniqueInfo() {
  TechniqueInfo info;
  info.name = "pcss";
  info.summary = "percentage-closer soft shadows: blocker search, penumbra width by similar triangles, PCF";
  info.source = "Fernando 2005 (modern baseline)";
  info.setOptions<PcssOptions>([](const PcssOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
