// Every parameter's documented range is one its technique survives: for every registered technique
// (the registry is iterated, so a new technique or parameter is covered without touching this file),
// each numeric parameter runs at both ends of its range and at three values between (geometric steps
// for a range spanning more than two decades, even steps otherwise), each bool at both values and each
// string at every choice, with every light shape and with lights at the ends of their own ranges.
// A run must end in V finite and in [0, 1] for every pixel, or in one Error that names what it
// refuses (a light shape); a crash or a sanitizer finding fails the suite (`make test-sanitize`).
//
// What keeps it fast enough to run under ASan on every commit: an 8 x 8 image (the per-pixel work
// is not what breaks at a range end; the light-space work is), the other parameters at their
// defaults except map_size at 64 texels, samples and spp at 4 where present. map_size itself runs
// with three lights, a rect, a segment and a directional one: a map's size enters only its
// projection, perspective for every light with a position and orthographic for a directional light,
// so those reach every code path a map size can. Its top end (8192 texels, 512 MB a map) runs once
// per technique, under the first of those lights it takes, with one light sample.
//
// A value inside a range that a technique refuses by a documented rule (pcf's kernel must be odd)
// may be refused with an Error naming the parameter; a range end never may.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "fuzz/technique_params_inputs.h"
#include "penumbra/error.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"

namespace penumbra {
namespace {

constexpr int kImageSize = 8;

// The values a parameter is swept over: its range ends and three between.
std::vector<ParamValue> sweepValues(const ParamSpec& spec) {
  switch (spec.type) {
    case ParamType::Bool:
      return {false, true};
    case ParamType::String: {
      std::vector<ParamValue> out;
      for (const std::string& choice : spec.choices) out.emplace_back(choice);
      return out;
    }
    case ParamType::Int:
    case ParamType::Float:
      break;
  }
  // Every numeric parameter must document both ends, so that "its range" means something.
  EXPECT_TRUE(spec.min && spec.max) << spec.name << ": a numeric parameter documents its range [min, max]";
  const double lo = spec.min.value_or(0.0), hi = spec.max.value_or(lo + 1.0);
  std::vector<double> points = {lo, hi};
  const bool geometric = lo > 0.0 && hi / lo > 100.0;
  for (double f : {0.25, 0.5, 0.75}) points.push_back(geometric ? lo * std::pow(hi / lo, f) : lo + f * (hi - lo));
  std::vector<ParamValue> out;
  for (double x : points) {
    if (spec.type == ParamType::Int) {
      out.emplace_back(static_cast<int64_t>(std::llround(x)));
    } else {
      out.emplace_back(x);
    }
  }
  return out;
}

struct SweepLight {
  std::string what;
  Light light;
  bool mapSizes = false;  //!< also runs the map_size values (see the file comment)
};

// Every shape above the small scene, then lights at the ends of their own ranges: a light far
// smaller than the scene, one far wider than it, a directional light near its widest angle and one of
// the narrowest, a segment much longer than the scene.
std::vector<SweepLight> sweepLights() {
  std::vector<SweepLight> lights;
  for (uint8_t k = 0; k < fuzz::kSmallSceneLightShapes; ++k) {
    const Light light = fuzz::smallSceneLight(k);
    const LightShape shape = light.shape();
    lights.push_back({std::string(toString(shape)), light,
                      shape == LightShape::Rect || shape == LightShape::Segment || shape == LightShape::Directional});
  }
  const Vec3 c = fuzz::kSmallSceneLightCenter;
  lights.push_back({"tiny sphere", Light::sphere(c, 1.0e-6f)});
  lights.push_back({"rect 100 wide", Light::rect(c, Vec3(50.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 50.0f))});
  lights.push_back({"directional 179 degrees", Light::directional(Vec3(0.0f, 1.0f, 0.0f), radians(179.0f))});
  lights.push_back({"directional 0.001 degrees", Light::directional(Vec3(0.0f, 1.0f, 0.0f), radians(0.001f))});
  lights.push_back({"segment 200 long", Light::segment(c - Vec3(100.0f, 0.0f, 0.0f), c + Vec3(100.0f, 0.0f, 0.0f))});
  return lights;
}

// Parameters a technique takes only together (brabec's paper knobs replace its derived search
// radius as a set): sweeping one gives the others a moderate 5 (in their units).
const std::vector<std::vector<std::string>> kGivenTogether = {{"r_scale", "r_bias", "r_shrink"}};

// The cheap defaults the swept parameter `swept` runs beside (see the file comment).
ParamSet cheapDefaults(const TechniqueInfo& info, const std::string& swept = {}) {
  ParamSet given;
  for (const auto& group : kGivenTogether)
    if (std::find(group.begin(), group.end(), swept) != group.end())
      for (const ParamSpec& spec : info.params)
        if (spec.name != swept && std::find(group.begin(), group.end(), spec.name) != group.end())
          given.set(spec.name, 5.0, "sweep");
  if (info.hasParam("map_size")) given.set("map_size", int64_t{64}, "sweep");
  if (info.hasParam("samples")) given.set("samples", int64_t{4}, "sweep");
  if (info.hasParam("spp")) given.set("spp", int64_t{4}, "sweep");
  return given;
}

struct Outcome {
  size_t runs = 0, refusals = 0;
};

// Runs `info` with `given` under `light`; checks V or the refusal. `interiorParam`: the swept
// parameter when its value lies inside its range (a documented rule may refuse it). Returns whether
// the technique ran.
bool runOnce(const TechniqueInfo& info, const ParamSet& given, const SweepLight& light, const GBuffer& gbuffer,
             const std::string& label, Outcome& outcome, const std::string& interiorParam = {}) {
  Params params;
  try {
    params = resolveParams(info.name, info.params, given);
  } catch (const Error& e) {
    ADD_FAILURE() << label << ": the schema refuses a value of its own range: " << e.what();
    return false;
  }
  const Scene scene = fuzz::smallScene(light.light);
  Image<float> v;
  ++outcome.runs;
  try {
    auto technique = info.create(params);
    technique->prepare(scene, light.light);
    technique->visibility(gbuffer, v);
  } catch (const Error& e) {
    const std::string message = e.what();
    if (!interiorParam.empty() && message.find(interiorParam + " = ") != std::string::npos) return false;
    ++outcome.refusals;
    // The only refusal a technique may make of a valid light and in-range parameters is its shape.
    EXPECT_NE(message.find(toString(light.light.shape())), std::string::npos)
        << label << ": refused with an Error that is not about the light's shape: " << message;
    return false;
  }
  if (v.width() != gbuffer.width() || v.height() != gbuffer.height()) {
    ADD_FAILURE() << label << ": V is " << v.width() << "x" << v.height() << ", not the G-buffer's size";
    return false;
  }
  size_t bad = 0;
  for (float x : v) bad += !(std::isfinite(x) && x >= 0.0f && x <= 1.0f);
  EXPECT_EQ(bad, 0u) << label << ": V must be finite and in [0, 1]";
  return true;
}

bool isRangeEnd(const ParamSpec& spec, const ParamValue& value) {
  if (spec.type == ParamType::Int) {
    const auto x = static_cast<double>(std::get<int64_t>(value));
    return x == *spec.min || x == *spec.max;
  }
  if (spec.type == ParamType::Float)
    return std::get<double>(value) == *spec.min || std::get<double>(value) == *spec.max;
  return true;  // every bool and choice is an end
}

TEST(ParamRanges, EveryParameterSurvivesItsRangeEndsUnderEveryLight) {
  const std::vector<SweepLight> lights = sweepLights();
  const GBuffer gbuffer = renderGBuffer(fuzz::smallScene(lights[0].light), kImageSize, kImageSize);
  for (const TechniqueInfo& info : techniqueRegistry()) {
    Outcome outcome;
    for (const ParamSpec& spec : info.params) {
      for (const ParamValue& value : sweepValues(spec)) {
        // The top map size has a test of its own below.
        if (spec.name == "map_size" && std::get<int64_t>(value) == static_cast<int64_t>(*spec.max)) continue;
        ParamSet given = cheapDefaults(info, spec.name);
        given.set(spec.name, value, "sweep");
        for (const SweepLight& light : lights) {
          if (spec.name == "map_size" && !light.mapSizes) continue;
          const std::string label =
              fmt::format("{} {}={} under a {} light", info.name, spec.name, formatParamValue(value), light.what);
          SCOPED_TRACE(label);
          runOnce(info, given, light, gbuffer, label, outcome, isRangeEnd(spec, value) ? std::string() : spec.name);
        }
      }
    }
    if (info.params.empty())
      for (const SweepLight& light : lights)
        runOnce(info, cheapDefaults(info), light, gbuffer, info.name + " under a " + light.what + " light", outcome);
    // A technique must run somewhere: a sweep that only ever met refusals would test nothing.
    EXPECT_GT(outcome.runs, outcome.refusals) << info.name;
    std::printf("[ swept    ] %-15s %4zu runs, %3zu refused for the light's shape\n", info.name.c_str(), outcome.runs,
                outcome.refusals);
  }
}

TEST(ParamRanges, TheLargestMapSize) {
  const std::vector<SweepLight> lights = sweepLights();
  const GBuffer gbuffer = renderGBuffer(fuzz::smallScene(lights[0].light), kImageSize, kImageSize);
  for (const TechniqueInfo& info : techniqueRegistry()) {
    for (const ParamSpec& spec : info.params) {
      if (spec.name != "map_size") continue;
      ParamSet given = cheapDefaults(info, spec.name);
      if (info.hasParam("samples")) given.set("samples", int64_t{1}, "sweep");
      given.set(spec.name, static_cast<int64_t>(*spec.max), "sweep");
      Outcome outcome;
      bool ran = false;
      for (const SweepLight& light : lights) {
        if (!light.mapSizes || ran) continue;
        const std::string label = fmt::format("{} map_size={} under a {} light", info.name, *spec.max, light.what);
        SCOPED_TRACE(label);
        ran = runOnce(info, given, light, gbuffer, label, outcome);
      }
      EXPECT_TRUE(ran) << info.name << " ran with none of the lights at map_size " << *spec.max;
    }
  }
}

}  // namespace
}  // namespace penumbra
