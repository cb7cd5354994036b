// Shading for display (include/penumbra/shade.h): radiance = albedo * (ambient + E_unshadowed * V)
// (docs/architecture.md, "Data flow"). Approximations: diffuse surfaces only, one light, no interreflection;
// the ambient term is constant (scene.ambient times the peak irradiance). Units: irradiance as
// Light::irradiance returns it; the output is relative radiance, exposure-normalized to [0, 1]
// for a fully lit receiver (values above 1 are clipped by the PNG writer).
#include "penumbra/shade.h"

#include <algorithm>
#include <vector>

#include <tbb/parallel_for.h>

#include "penumbra/error.h"

namespace penumbra {

namespace {

// The q-quantile of values (0 for an empty list); nth_element keeps it O(n) and deterministic.
float quantile(std::vector<float> values, double q) {
  if (values.empty()) return 0.0f;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

Image<Vec3> shade(const Scene& scene, const Light& light, const GBuffer& gbuffer, const Image<float>& v,
                  const ShadeOptions& options) {
  const int width = gbuffer.width(), height = gbuffer.height();
  if (v.width() != width || v.height() != height)
    fail("shade: visibility image is {}x{} but the G-buffer is {}x{}", v.width(), v.height(), width, height);
  if (!(options.exposureQuantile > 0.0 && options.exposureQuantile <= 1.0))
    fail("shade: exposureQuantile must be in (0, 1] (got {})", options.exposureQuantile);

  // Per pixel albedo and unshadowed irradiance; the irradiance of planar lights is a 64-sample
  // quadrature, so this loop is worth spreading over threads.
  Image<float> irradiance(width, height, 0.0f);
  Image<Vec3> albedo(width, height, Vec3(0.0f));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const Object* object = scene.findObject(gbuffer.objectId(x, y));
      if (!object)
        fail("shade: the G-buffer names object id {} at pixel ({}, {}), which is not in scene '{}'",
             gbuffer.objectId(x, y), x, y, scene.name);
      albedo(x, y) = object->albedo;
    }
  tbb::parallel_for(0, height, [&](int y) {
    for (int x = 0; x < width; ++x)
      if (gbuffer.hit(x, y)) irradiance(x, y) = light.irradiance(gbuffer.wsPosition(x, y), gbuffer.wsNormal(x, y));
  });

  std::vector<float> hitIrradiance;
  for (size_t i = 0; i < irradiance.size(); ++i)
    if (gbuffer.objectId[i] != kNoObject) hitIrradiance.push_back(irradiance[i]);
  float peak = quantile(hitIrradiance, options.exposureQuantile);
  // Nothing lit (light behind every surface, or an empty scene): keep the ambient term meaningful
  // by measuring it against unit irradiance.
  if (!(peak > 0.0f)) peak = 1.0f;
  const float ambient = scene.ambient * peak;

  std::vector<float> unshadowed;
  unshadowed.reserve(hitIrradiance.size());
  for (size_t i = 0; i < irradiance.size(); ++i)
    if (gbuffer.objectId[i] != kNoObject) {
      const Vec3 l = albedo[i] * (ambient + irradiance[i]);
      unshadowed.push_back(std::max(l.x, std::max(l.y, l.z)));
    }
  const float white = quantile(std::move(unshadowed), options.exposureQuantile);
  const float exposure = white > 0.0f ? 1.0f / white : 1.0f;

  Image<Vec3> rgb(width, height, options.background);
  for (size_t i = 0; i < rgb.size(); ++i)
    if (gbuffer.objectId[i] != kNoObject) rgb[i] = exposure * albedo[i] * (ambient + irradiance[i] * v[i]);
  return rgb;
}

}  // namespace penumbra
