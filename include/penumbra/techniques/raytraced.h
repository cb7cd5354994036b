// The few-ray family's typed options and factories (docs/techniques.md): raytraced-soft (a few rays
// per pixel and a penumbra-aware filter) and hybrid (a shadow map answers lit and umbra, rays the
// rest). See shadow_map.h of this folder for how options and factories are used.
#pragma once

#include <cstdint>
#include <memory>

#include "penumbra/options.h"
#include "penumbra/technique.h"
#include "penumbra/techniques/shadow_map.h"

namespace penumbra {

struct PenumbraFilterOptions {
  float filterScale = 0.25f;     //!< filter radius over the estimated penumbra width (both in pixels)
  float minRadius = 2.0f;        //!< filter radius floor in penumbra tiles, pixels
  float maxRadius = 48.0f;       //!< filter radius cap, pixels
  int tapsPerSide = 8;           //!< taps on each side of the centre per pass
  float planeTolerance = 0.25f;  //!< plane distance tolerated, in pixel footprints per pixel of distance
  int normalPower = 16;          //!< exponent of the normal weight

  static void describe(OptionFields<PenumbraFilterOptions>& f) {
    f.add(&PenumbraFilterOptions::filterScale,
          OptionDecl("filter_scale")
              .range(0.0, 4.0)
              .help("filter radius as a multiple of the estimated penumbra width (0 turns the filter off)"));
    f.add(
        &PenumbraFilterOptions::minRadius,
        OptionDecl("min_radius")
            .range(0.0, 256.0)
            .unit("pixels")
            .help("smallest filter radius of a penumbra tile's pixel that has a lit ray, so that a penumbra a pixel or "
                  "two wide still averages its neighbours' rays (2: taps 1 pixel away weigh 0.56; at 2 rays per pixel, "
                  "scaled by sqrt(2 / spp)); a pixel all of "
                  "whose rays were blocked keeps its own radius, so umbra does not light up at sharp contacts"));
    f.add(&PenumbraFilterOptions::maxRadius,
          OptionDecl("max_radius").range(1.0, 256.0).unit("pixels").help("largest filter radius"));
    f.add(&PenumbraFilterOptions::tapsPerSide,
          OptionDecl("taps_per_side")
              .range(1, 64)
              .unit("taps")
              .help("taps on each side of a pixel per separable pass (wider radii read every stride-th pixel)"));
    f.add(&PenumbraFilterOptions::planeTolerance,
          OptionDecl("plane_tolerance")
              .range(0.01, 1000.0)
              .unit("pixel footprints per pixel")
              .help("edge stop: distance of a tap from the pixel's tangent plane tolerated, per pixel of distance"));
    f.add(&PenumbraFilterOptions::normalPower,
          OptionDecl("normal_power").range(0, 1024).help("edge stop: exponent of max(0, n_p . n_q)"));
  }
};

// Temporal accumulation, for a technique instance run frame after frame (a sequence: the light or the
// camera moving). Engines' shadow denoisers do it (SIGMA, FidelityFX): each pixel's V is blended with
// its history, found by reprojecting the pixel's world position into the previous frame's camera
// (valid where that pixel saw the same object within two pixel footprints of it), and clamped to the
// range of this frame's V over the pixel's 3 x 3 neighbourhood (same object), widened by a margin, so
// that a shadow that moved leaves no ghost behind:
//     V = h + alpha (V_now - h),   h = clamp(V_prev(reprojected), min3x3(V_now) - m, max3x3(V_now) + m).
// The margin m is there because a few rays' filtered V still carries noise wider than a 3 x 3 range:
// clamped to that range alone, the history follows this frame's noise, and the sequence flickers as
// much as without it (tests/techniques/raytraced/raytraced_soft_test.cpp measures both).
// Where the history is not valid (disocclusion, the first frame) V_now is kept. With it on, each frame
// draws new sample patterns (the seed combined with the frame's index), so the history averages
// independent noise. A frame then depends on the frames before it: a sequence run from its first
// frame is deterministic, one frame run alone is not the same as that frame in a sequence.
struct TemporalOptions {
  bool enabled = false;      //!< blend with the reprojected history
  float alpha = 0.2f;        //!< weight of the new frame
  float clampMargin = 0.1f;  //!< widening of the history's clamp range, V

  static void describe(OptionFields<TemporalOptions>& f) {
    f.add(&TemporalOptions::enabled,
          OptionDecl("temporal")
              .help("accumulate over frames: blend V with its history, reprojected through world positions and "
                    "clamped to this frame's 3x3 range widened by temporal_clamp_margin; new sample patterns each "
                    "frame"));
    f.add(&TemporalOptions::alpha, OptionDecl("temporal_alpha")
                                       .range(0.01, 1.0)
                                       .help("weight of the new frame in the temporal blend (1: no history)"));
    f.add(&TemporalOptions::clampMargin,
          OptionDecl("temporal_clamp_margin")
              .range(0.0, 1.0)
              .help("the history is clamped to this frame's 3x3 range of V widened by this much (V units): 0 follows "
                    "this frame's noise, 1 keeps ghosts"));
  }
};

struct RaytracedSoftOptions {
  int samplesPerPixel = 2;       //!< rays per pixel of a penumbra tile
  bool skipUniformTiles = true;  //!< tiles whose probes agree with their neighbours' trace no more rays
  uint64_t seed = 1;             //!< selects the sample patterns
  PenumbraFilterOptions filter;
  TemporalOptions temporal;

  static void describe(OptionFields<RaytracedSoftOptions>& f) {
    f.add(
        &RaytracedSoftOptions::samplesPerPixel,
        OptionDecl("spp").range(1, 16).unit("rays").help(
            "shadow rays per pixel of a penumbra tile (CMJ-stratified over the light); elsewhere one probe ray per 2x2 "
            "pixels"));
    f.add(&RaytracedSoftOptions::skipUniformTiles,
          OptionDecl("skip_uniform_tiles")
              .help("8x8 tiles whose probe rays are all lit or all blocked, as are their neighbours', keep the "
                    "probe's answer: no more rays, no filter"));
    f.add(&RaytracedSoftOptions::seed,
          OptionDecl("seed").range(0, 4294967295.0).help("random seed; the same seed gives bit-identical output"));
    f.nest(&RaytracedSoftOptions::filter);
    f.nest(&RaytracedSoftOptions::temporal);
  }
};

struct HybridOptions {
  LightMapOptions lightMap;  //!< the light map: size and fit
  DepthBias bias;            //!< depth-compare bias (shadow_map.h)
  int blockerSamples = 16;   //!< taps of the blocker search
  int samplesPerPixel = 2;   //!< rays per pixel of a penumbra tile
  uint64_t seed = 1;         //!< selects the sample patterns
  PenumbraFilterOptions filter;
  TemporalOptions temporal;

  static void describe(OptionFields<HybridOptions>& f) {
    f.nest(&HybridOptions::lightMap);
    f.nest(&HybridOptions::bias);
    f.add(&HybridOptions::blockerSamples,
          OptionDecl("blocker_samples")
              .range(1, 1024)
              .unit("samples")
              .help("taps of the blocker search that classifies a pixel lit, umbra or uncertain (Vogel disk)"));
    f.add(&HybridOptions::samplesPerPixel,
          OptionDecl("spp").range(1, 16).unit("rays").help(
              "shadow rays per pixel of a penumbra tile (CMJ-stratified over the light; none elsewhere)"));
    f.add(&HybridOptions::seed,
          OptionDecl("seed").range(0, 4294967295.0).help("random seed; the same seed gives bit-identical output"));
    f.nest(&HybridOptions::filter);
    f.nest(&HybridOptions::temporal);
  }
};

// The technique made from its options (the registry makes the same from parameters by name).
std::unique_ptr<ShadowTechnique> makeTechnique(const RaytracedSoftOptions& options);  // raytraced-soft
std::unique_ptr<ShadowTechnique> makeTechnique(const HybridOptions& options);         // hybrid

}  // namespace penumbra
