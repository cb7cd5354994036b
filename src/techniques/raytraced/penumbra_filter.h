// The penumbra-aware spatial filter of the few-ray techniques (raytraced-soft, hybrid): a
// cross-bilateral filter in screen space whose radius at each pixel follows that pixel's estimated
// penumbra width, so contact shadows stay sharp and wide penumbrae get wide support.
//
// What it follows (read to understand; the code is ours):
//  - Mehta, Wang, Ramamoorthi and Durand 2012, "Axis-Aligned Filtering for Interactive Sampled Soft
//    Shadows": visibility behind a blocker at distance d_b from a receiver, under a light of size L
//    at distance d_l, is band-limited by the light's projection through the blocker, a kernel of
//    width L d_b / (d_l - d_b) on the receiver; a screen-space Gaussian of that scale removes the
//    sampling noise without blurring the shadow more than the light itself does. AAF derives the
//    scale from the minimum and maximum blocker distances per pixel; we use the mean of the hit
//    distances of the pixel's blocked rays.
//  - The published descriptions of NVIDIA's SIGMA (NRD) and AMD's FidelityFX Shadow Denoiser: the
//    penumbra size from ray hit distances, the filter only on tiles that are not wholly lit or
//    wholly in umbra, edge-stopping weights on plane distance and normal. Both also accumulate over
//    frames; this filter is spatial only.
//
// Weights of a tap q for the pixel p (all multiply):
//  - a biweight in screen distance d, (1 - d^2 / radius(p)^2)^2, taps out to radius(p) (smooth and
//    compact, close to a Gaussian of sigma radius(p) / 2 cut there, without an exp per tap);
//  - same object id (shadows never leak from an occluder onto the floor it stands on, or back);
//  - plane distance: |n_p . (x_q - x_p)| against `plane_tolerance` pixel footprints per pixel of d,
//    so a depth discontinuity within one object (a torus's near side over its far side) stops it;
//  - normals: max(0, n_p . n_q)^`normal_power`;
//  - reach: a tap all of whose rays were blocked counts only within its own radius (d <= reach(q)),
//    so the umbra under a narrow contact penumbra does not bleed into the wide penumbra next to it.
// Separable: a horizontal pass, then a vertical pass over its result, with the same radius at p
// (exact for a constant radius; for a varying one an approximation engines accept). Taps are spaced
// so that at most 2 `taps_per_side` + 1 are read per pass, which for wide radii samples every
// stride-th pixel; the noise being independent per pixel, that still averages it.
#pragma once

#include <cstdint>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/options.h"
#include "penumbra/techniques/raytraced.h"

namespace penumbra::raytraced {

using penumbra::PenumbraFilterOptions;  // include/penumbra/techniques/raytraced.h
using penumbra::TemporalOptions;

// What the filter reads per pixel besides the G-buffer.
struct PenumbraFilterInput {
  const Image<float>* noisy = nullptr;   //!< V estimated by the pixel's own rays
  const Image<float>* radius = nullptr;  //!< filter radius, pixels; below 1: the pixel is left as it is
  const Image<float>* reach = nullptr;   //!< how far the pixel may contribute, pixels (kInfinity: anywhere)
  float tanHalfFovY = 0.0f;              //!< the camera's, for a pixel's footprint from its view depth
  // Optional: the square tiles (tileSize pixels a side, tilesX to a row, row-major) that hold every
  // pixel of radius >= 1; the passes visit only those. Null: every pixel is visited.
  const uint8_t* activeTiles = nullptr;
  int tileSize = 0, tilesX = 0;
};

// Writes the filtered V into `out` (resized to the G-buffer's size); `scratch` holds the first pass
// (its storage reused across calls). Deterministic: each output pixel is a fixed sum over its taps,
// whatever the thread count.
void filterPenumbrae(const GBuffer& gbuffer, const PenumbraFilterInput& input, const PenumbraFilterOptions& options,
                     Image<float>& scratch, Image<float>& out);

// The world size of one pixel at view depth csDepth, for an image `height` pixels tall.
inline float pixelFootprint(float csDepth, float tanHalfFovY, int height) {
  return csDepth * 2.0f * tanHalfFovY / static_cast<float>(height);
}

}  // namespace penumbra::raytraced
