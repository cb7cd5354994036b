// Shading of one frame (docs/architecture.md, "Data flow"): radiance = albedo * (ambient + E_unshadowed * V),
// a diffuse surface lit by one light whose unshadowed irradiance E is scaled by the visibility V of
// a technique. Only for looking at results: the error metric compares V, never these colours.
#pragma once

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra {

struct ShadeOptions {
  Vec3 background{0.02f, 0.02f, 0.025f};  //!< linear RGB of pixels that see nothing
  // Exposure: the image is scaled so that this quantile of the unshadowed radiance (max channel,
  // over hit pixels) maps to 1. Below 1 so a few hot pixels next to a local light do not darken
  // the whole image; those few clip, a fully lit receiver does not. In (0, 1].
  double exposureQuantile = 0.99;
};

// Linear RGB radiance per pixel, exposure-normalized (see ShadeOptions). The ambient term is
// scene.ambient times the peak irradiance (the same quantile of E over hit pixels), so it is
// relative to the light as Scene::ambient documents. v must have the G-buffer's size; every hit
// object id must be in the scene. Throws Error otherwise.
Image<Vec3> shade(const Scene& scene, const Light& light, const GBuffer& gbuffer, const Image<float>& v,
                  const ShadeOptions& options = {});

}  // namespace penumbra
