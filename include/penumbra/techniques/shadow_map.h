// The shadow-map family's typed options and factories (docs/techniques.md): hard, pcf, pcss,
// multisample, brabec (Brabec & Seidel 2002) and heidrich (Heidrich, Brabec & Seidel 2000). Each options
// struct holds one member per parameter, its initializer the default, and describe() the name, range,
// unit and help from which the registry's schema is generated (options.h): a program sets the members
// and calls makeTechnique, the CLI and scene files give the same parameters by name.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "penumbra/options.h"
#include "penumbra/raster.h"
#include "penumbra/technique.h"

namespace penumbra {

inline constexpr int kMinShadowMapSize = 16;
inline constexpr int kMaxShadowMapSize = 8192;

// Depth bias of the compare (see the file comment); every shadow-map technique nests it in its
// options, so bias_constant and bias_slope read the same everywhere.
struct DepthBias {
  float constantTexels = 0.5f;  //!< in texel sizes at the receiver's depth (world size of one texel)
  float slope = 1.0f;           //!< multiplies the receiver plane's depth change per texel

  static void describe(OptionFields<DepthBias>& f) {
    f.add(&DepthBias::constantTexels,
          OptionDecl("bias_constant")
              .range(0, 64)
              .unit("texels")
              .help("constant depth bias, in world sizes of one texel at the receiver's depth"));
    f.add(&DepthBias::slope, OptionDecl("bias_slope")
                                 .range(0, 64)
                                 .help("slope-scaled depth bias: multiplies the receiver's depth change per texel"));
  }
};

// The light map every light-map technique renders: its size and how it is fitted to the scene
// (renderLightMap). Every light-map technique nests it in its options, so map_size and map_fit read
// the same everywhere.
struct LightMapOptions {
  int size = 1024;                           //!< texels per side
  LightMapFit fit = LightMapFit::Tight;      //!< how the map is fitted each frame (raster.h)
  HorizonClamp horizon = HorizonClamp::Off;  //!< bound V by the receiver's own surface (core/horizon.h)

  static void describe(OptionFields<LightMapOptions>& f) {
    f.add(&LightMapOptions::size, OptionDecl("map_size")
                                      .range(kMinShadowMapSize, kMaxShadowMapSize)
                                      .unit("texels")
                                      .help("width and height of the square light-space depth map"));
    f.add(&LightMapOptions::fit,
          OptionDecl("map_fit").help(
              "how the light map is fitted to the scene each frame: tight (refitted from the light's centre: finest "
              "texels, the grid moves with the light), stable (quantized axis and extent, origin snapped to whole "
              "texels: the map holds still under small light motion; texels coarser by up to an extent step of 4.4% "
              "plus what the quantized axis's tilt costs) or aligned (stable, along the world axis nearest the light's "
              "direction to the scene where one lies within 30 degrees, as a cube map's face, the window centred on "
              "the scene and the grid fixed at its far face: the floor keeps its texels as the light moves)"),
          {{"tight", LightMapFit::Tight}, {"stable", LightMapFit::Stable}, {"aligned", LightMapFit::Aligned}});
    f.add(&LightMapOptions::horizon,
          OptionDecl("horizon").help(
              "bound V by the receiver's own surface, which a map seen from the light's centre cannot see: off "
              "(the paper's V), facing (V = 0 where the receiver's face turns from the light's centre: beside a "
              "smooth model's terminator its solid hides the light, as the reference finds) or plane (V at most "
              "the share of the light above the plane of the receiver's face)"),
          {{"off", HorizonClamp::Off}, {"facing", HorizonClamp::Facing}, {"plane", HorizonClamp::Plane}});
  }
};

// The light map of the soft single-sample techniques pcf, pcss, plm, smoothies and kirsch: the same,
// with `horizon` facing. Next to a smooth model's terminator, facets turned from the light's centre
// (their shading normals still facing it) are lit through a map seen from that centre, where the
// reference finds them in their own solid's shadow: most of the umbra leaks of these techniques on the
// real-mesh corpus (docs/real-meshes.md). `plane` bounds V by the share above the face's plane instead;
// against the reference it does worse, since a face turned towards the light's centre does not shadow
// itself there (the reference's rays leave from the light's side of it, rt::lightSide), as the smooth
// surface it stands for would not. Off by default elsewhere: a hard shadow (`hard`) is one point's
// visibility and multisample's V a count of its point samples; brabec applies the facing rule itself;
// heidrich and hybrid are left as they were measured. The papers' reproductions set it off.
inline constexpr LightMapOptions kSoftLightMap{.horizon = HorizonClamp::Facing};

struct HardShadowOptions {
  LightMapOptions lightMap;  //!< the light map: size and fit
  DepthBias bias;            //!< depth-compare bias (shadow_map.h)

  static void describe(OptionFields<HardShadowOptions>& f) {
    f.nest(&HardShadowOptions::lightMap);
    f.nest(&HardShadowOptions::bias);
  }
};

struct PcfOptions {
  LightMapOptions lightMap = kSoftLightMap;  //!< the light map: size, fit and horizon
  int kernel = 3;                            //!< width of the box kernel in texels, odd
  DepthBias bias;                            //!< depth-compare bias (shadow_map.h)

  static void describe(OptionFields<PcfOptions>& f) {
    f.nest(&PcfOptions::lightMap);
    f.add(&PcfOptions::kernel, OptionDecl("kernel").range(1, 63).unit("texels").help(
                                   "width of the box kernel (odd); border texels weigh their covered fraction"));
    f.nest(&PcfOptions::bias);
  }
};

struct PcssOptions {
  LightMapOptions lightMap = kSoftLightMap;  //!< the light map: size, fit and horizon
  int blockerSamples = 16;                   //!< taps of the blocker search
  int filterSamples = 32;                    //!< taps of the PCF filter
  std::optional<float> lightSize;  //!< light radius, world units (directional: tan of the half angle); empty =
                                   //!< Light::extent() (segment, rect: as the map sees it, file comment)
  bool rotate = true;              //!< rotate the sample disks per pixel by a hash
  float bilinearMaxRadius = 4.0f;  //!< filter radius, texels, up to which taps are bilinear (wider: nearest texel)
  DepthBias bias;                  //!< depth-compare bias (shadow_map.h)

  static void describe(OptionFields<PcssOptions>& f) {
    f.nest(&PcssOptions::lightMap);
    f.add(&PcssOptions::blockerSamples,
          OptionDecl("blocker_samples").range(1, 1024).unit("samples").help("taps of the blocker search (Vogel disk)"));
    f.add(&PcssOptions::filterSamples,
          OptionDecl("filter_samples")
              .range(1, 1024)
              .unit("samples")
              .help("taps of the PCF filter (Vogel disk; bilinear compares up to bilinear_max_radius)"));
    f.add(
        &PcssOptions::lightSize,
        OptionDecl("light_size")
            .range(1e-6, 1e6)
            .unit("world units")
            .help(
                "light radius (directional: tan of half the angular diameter); auto = the light's extent (segment: its "
                "half-length, rect: its larger half-diagonal, both foreshortened as the map sees them); a search or "
                "filter radius wider than the map is clamped to the map's size (stat frac_clamped_to_map)"));
    f.add(
        &PcssOptions::rotate,
        OptionDecl("rotate").help("rotate the sample disks per pixel by a hash (noise instead of banding); segment and "
                                  "rect lights keep their orientation"));
    f.add(&PcssOptions::bilinearMaxRadius,
          OptionDecl("bilinear_max_radius")
              .range(0, kMaxShadowMapSize)
              .unit("texels")
              .help("filter radius up to which each filter tap is a bilinear 2x2 compare; wider filters use one "
                    "nearest-texel compare per tap (8192: always bilinear)"));
    f.nest(&PcssOptions::bias);
  }
};

struct MultisampleOptions {
  LightMapOptions lightMap;  //!< each sample's light map: size and fit
  int samples = 16;          //!< light samples = shadow maps
  uint32_t seed = 1;         //!< selects the stratified sample pattern
  DepthBias bias;            //!< depth-compare bias (shadow_map.h)

  static void describe(OptionFields<MultisampleOptions>& f) {
    f.nest(&MultisampleOptions::lightMap);
    f.add(&MultisampleOptions::samples, OptionDecl("samples").range(1, 1024).unit("samples").help(
                                            "light samples, one shadow map each (CMJ-stratified over the emitter)"));
    f.add(&MultisampleOptions::seed,
          OptionDecl("seed").range(0, 4294967295.0).help("selects the stratified sample pattern"));
    f.nest(&MultisampleOptions::bias);
  }
};

struct BrabecOptions {
  LightMapOptions lightMap;         //!< light depth/id map (the paper: 256 texels a side for 512x512 images)
  DepthBias bias;                   //!< of the hard test and of the searches' depth layer
  float meet = 0.5f;                //!< V on the hard-shadow edge, where inner and outer penumbra meet
  std::optional<float> rScale;      //!< paper: search radius per world unit of |z|, texels / world unit
  std::optional<float> rBias;       //!< paper: search radius at z = 0, texels
  std::optional<float> rShrink;     //!< paper: r_max factor per world unit of depth difference, 1 / world unit
  int maxRadius = 96;               //!< hard cap of the search radius, texels (see the file comment)
  bool interpolate = true;          //!< Sec. 4.3 adaptive block interpolation
  int interpolateBlock = 0;         //!< block side, pixels; 0: from the image size (brabec.h, "Adaptive sampling")
  float interpolateMaxStep = 1.0f;  //!< also refine a group whose border V differ by more
  bool interpolateKinks = true;  //!< also refine across the kinks of V (r = r_max, ridges of r); see the file comment
  float interpolateMaxAngle = 30.0f;  //!< kinks: largest angle between the borders' directions to their texels, degrees
  float jitter = 0.0f;                //!< texel position jitter amplitude, texels
  bool idTest = true;                 //!< the object-id test of Sec. 3.2 (false reproduces Fig. 3's self-shadowing)
  bool scalarSearch = false;          //!< not a parameter: the scalar search that checks the vectorized one (same V)
  bool accelerate = true;             //!< tiles + local search radius (cost only); false: the plain Sec. 4.2 search
  bool coverageBound = true;   //!< our extension: V >= 1 - blocked fraction of the light's footprint (file comment)
  int coverageMinTexels = 32;  //!< coverage bound: smallest footprint applied at, texels (segment: samples)
  int coverageSamples = 256;   //!< coverage bound: most texels counted per footprint (wider: a sparser lattice)

  static void describe(OptionFields<BrabecOptions>& f) {
    using O = BrabecOptions;
    f.nest(&O::lightMap);
    f.nest(&O::bias);
    f.add(&O::meet, OptionDecl("meet").range(0, 1).help(
                        "V on the hard-shadow edge, where the inner and the outer penumbra meet (Sec. 3.3)"));
    f.add(&O::rScale,
          OptionDecl("r_scale")
              .range(0, 1e6)
              .unit("texels per world unit")
              .help("paper's knob: search radius r_scale |z| + r_bias; auto derives r_max from the light's size "
                    "(give r_scale, r_bias and r_shrink together)"));
    f.add(&O::rBias, OptionDecl("r_bias").range(0, 1e6).unit("texels").help(
                         "paper's knob: search radius at depth 0 (with r_scale and r_shrink)"));
    f.add(&O::rShrink,
          OptionDecl("r_shrink")
              .range(0, 1e6)
              .unit("1 / world unit")
              .help("paper's knob: r_max = search radius * r_shrink * depth difference once a texel is found "
                    "(with r_scale and r_bias)"));
    f.add(
        &O::maxRadius,
        OptionDecl("max_radius")
            .range(1, 1024)
            .unit("texels")
            .help(
                "hard cap of the search radius: bounds the cost of a pixel (it grows with the radius squared) when the "
                "nearest possible blocker sits close to the light; beyond it a penumbra is cut. 96 holds the widest "
                "physical radius of the built-in scenes at map_size 1024 (69 texels, `linear`)"));
    f.add(&O::interpolate,
          OptionDecl("interpolate").help("adaptive block interpolation (Sec. 4.3); false searches every pixel"));
    f.add(&O::interpolateBlock,
          OptionDecl("interpolate_block")
              .range(0, 64)
              .unit("pixels")
              .help("side of the interpolation's blocks (searched borders every this many pixels); 0 = auto: 4 on "
                    "images up to 1023 pixels on their longer side, the paper's 4 x 4 at 512 x 512 and 800 x 600, "
                    "doubled at every doubling of it (8 at 1024, 16 at 2048), as Sec. 4.3 says the block should "
                    "depend on the image size"));
    f.add(&O::interpolateMaxStep,
          OptionDecl("interpolate_max_step")
              .range(0, 1)
              .help("also search the middle of a group whose border V differ by more than this; 1 = off"));
    f.add(&O::interpolateKinks,
          OptionDecl("interpolate_kinks")
              .help("also search the middle of a group across a kink of V: one border at the end of the penumbra (r >= "
                    "r_max) and the other not, or the borders' nearest texels in directions more than "
                    "interpolate_max_angle apart (a ridge of the distance field); false = the paper's criteria"));
    f.add(&O::interpolateMaxAngle,
          OptionDecl("interpolate_max_angle")
              .range(0, 180)
              .unit("degrees")
              .help("interpolate_kinks: largest angle between the directions from the two borders to the texels their "
                    "searches found"));
    f.add(&O::accelerate,
          OptionDecl("accelerate")
              .help("tile summary and local search radius: change the cost, never V; false runs the plain "
                    "Sec. 4.2 search (for measuring what they save)"));
    f.add(&O::jitter,
          OptionDecl("jitter").range(0, 0.5).unit("texels").help(
              "jitter of the texel positions the distances are measured to (Sec. 4.3), deterministic; 0 = off"));
    f.add(&O::idTest, OptionDecl("id_test").help(
                          "object-id test of the searches (Sec. 3.2); false shows the self-shadowing of Fig. 3"));
    f.add(
        &O::coverageBound,
        OptionDecl("coverage_bound")
            .help(
                "our extension, not the paper's: V is at least 1 - f, f the fraction of the texels in the light's "
                "footprint at the blocker's silhouette depth (its shape scaled to the penumbra width there) that block "
                "the receiver; lightens the dark blob of an occluder smaller than the light (see "
                "docs/small-occluders.md); false = the paper's V"));
    f.add(
        &O::coverageMinTexels,
        OptionDecl("coverage_min_texels")
            .range(1, 1e6)
            .unit("texels")
            .help(
                "coverage_bound: smallest footprint (texels; samples along a segment light) the bound is applied at; "
                "smaller footprints cannot resolve the covered fraction (contact shadows, small maps). 32: measured on "
                "the corpus, teapots and the built-in scenes, see docs/small-occluders.md"));
    f.add(
        &O::coverageSamples,
        OptionDecl("coverage_samples")
            .range(16, 1e6)
            .unit("texels")
            .help(
                "coverage_bound: most texels counted per footprint; a wider footprint is counted on a lattice of every "
                "k-th texel in s and t. 256 resolves the covered fraction to about one 8-bit step; measured: RMSE8 "
                "within 0.1 of the full count on every scene and light of docs/small-occluders.md"));
  }
};

struct HeidrichOptions {
  LightMapOptions lightMap;    //!< each sample point's shadow and visibility map: size and fit
  int subdivisions = 1;        //!< k: sub-segments of the light (k + 1 sample points)
  float edgeThreshold = 4.0f;  //!< smallest depth gap that is a discontinuity, in texel sizes at its depth
  DepthBias bias;              //!< depth-compare bias of the shadow-map channel (shadow_map.h)

  static void describe(OptionFields<HeidrichOptions>& f) {
    f.nest(&HeidrichOptions::lightMap);
    f.add(&HeidrichOptions::subdivisions,
          OptionDecl("subdivisions")
              .range(1, 64)
              .unit("sub-segments")
              .help("k: the segment is split into k linear lights (k + 1 sample points, one shadow map each); raise it "
                    "where part of the light shows between occluders that hide both end points"));
    f.add(&HeidrichOptions::edgeThreshold,
          OptionDecl("edge_threshold")
              .range(0.01, 1000)
              .unit("texels")
              .help("smallest depth gap treated as a discontinuity (skin polygons), in world sizes of one texel at its "
                    "depth"));
    f.nest(&HeidrichOptions::bias);
  }
};

// The technique made from its options (the registry makes the same from parameters by name).
std::unique_ptr<ShadowTechnique> makeTechnique(const HardShadowOptions& options);   // hard
std::unique_ptr<ShadowTechnique> makeTechnique(const PcfOptions& options);          // pcf
std::unique_ptr<ShadowTechnique> makeTechnique(const PcssOptions& options);         // pcss
std::unique_ptr<ShadowTechnique> makeTechnique(const MultisampleOptions& options);  // multisample
std::unique_ptr<ShadowTechnique> makeTechnique(const BrabecOptions& options);       // brabec
std::unique_ptr<ShadowTechnique> makeTechnique(const HeidrichOptions& options);     // heidrich

}  // namespace penumbra
