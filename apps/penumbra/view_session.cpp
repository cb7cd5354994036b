// ViewSession (view_session.h): the frames of `penumbra view`.
#include "view_session.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "eval/report_figures.h"
#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/shade.h"
#include "penumbra/timer.h"

namespace penumbra::cli {

namespace {

using nlohmann::json;

// The signed error map saturates at this |V - V_ref| (the report's default --error-range).
constexpr double kErrorRange = 0.5;
// The reference's batches: the first after a change is small, so that a moving view still shows a
// (noisy) reference at once; each later one doubles, up to this many samples per pixel.
constexpr uint32_t kFirstBatch = 2;
constexpr uint32_t kLargestBatch = 64;

constexpr LightShape kShapes[] = {LightShape::Sphere,  LightShape::Disk,    LightShape::Rect,
                                  LightShape::Segment, LightShape::Polygon, LightShape::Directional};

json toJson(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

Vec3 readVec3(const json& object, const char* field, const std::string& where) {
  const auto it = object.find(field);
  if (it == object.end() || !it->is_array() || it->size() != 3)
    fail("{}.{}: expected an array of 3 numbers", where, field);
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    const json& x = (*it)[static_cast<size_t>(i)];
    if (!x.is_number() || !std::isfinite(x.get<double>())) fail("{}.{}: expected 3 finite numbers", where, field);
    v[i] = x.get<float>();
  }
  return v;
}

double readNumber(const json& object, const char* field, const std::string& where) {
  const auto it = object.find(field);
  if (it == object.end() || !it->is_number() || !std::isfinite(it->get<double>()))
    fail("{}.{}: expected a finite number", where, field);
  return it->get<double>();
}

const json& readObject(const json& object, const char* field, const std::string& where) {
  const auto it = object.find(field);
  if (it == object.end() || !it->is_object()) fail("{}.{}: expected an object", where, field);
  return *it;
}

std::string readString(const json& object, const char* field, const std::string& where) {
  const auto it = object.find(field);
  if (it == object.end() || !it->is_string()) fail("{}.{}: expected a string", where, field);
  return it->get<std::string>();
}

bool sameCamera(const Camera& a, const Camera& b) {
  return a.position == b.position && a.lookAt == b.lookAt && a.up == b.up && a.fovYDegrees == b.fovYDegrees;
}

bool sameLight(const ViewRequest& a, const ViewRequest& b) {
  return a.lightIndex == b.lightIndex && a.shape == b.shape && a.lightPosition == b.lightPosition &&
         a.lightSize == b.lightSize;
}

// The size a request gives for the scene's own light (view_session.h, ViewRequest::lightSize).
float baseSize(const Light& light) {
  switch (light.shape()) {
    case LightShape::Sphere:
    case LightShape::Disk:
      return light.radius();
    case LightShape::Rect:
      return std::max(glm::length(light.u()), glm::length(light.v()));
    case LightShape::Segment:
      return 0.5f * glm::length(light.b() - light.a());
    case LightShape::Polygon:
      return light.extent();
    case LightShape::Directional:
      return glm::degrees(light.angularDiameter());
  }
  return light.extent();
}

json schemaJson(const ParamSpec& spec) {
  json p = {{"name", spec.name},        {"type", std::string(toString(spec.type))},
            {"auto", spec.autoDefault}, {"unit", spec.unit},
            {"help", spec.help},        {"choices", spec.choices}};
  p["default"] = spec.autoDefault ? json("auto") : json(formatParamValue(spec.defaultValue));
  p["min"] = spec.min ? json(*spec.min) : json(nullptr);
  p["max"] = spec.max ? json(*spec.max) : json(nullptr);
  return p;
}

ViewImage makeImage(int width, int height, int channels, std::vector<uint8_t> bytes, FrameEncoding encoding) {
  ViewImage image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.png = encoding == FrameEncoding::Png;
  image.bytes = image.png ? encodePng(width, height, channels, bytes) : std::move(bytes);
  return image;
}

}  // namespace

ViewSession::ViewSession(Scene scene, const Options& options)
    : scene_(std::move(scene)), options_(options), reference_(ReferenceOptions{}) {
  if (options_.width < 1 || options_.height < 1)
    fail("view: image size {}x{} is empty", options_.width, options_.height);
  if (options_.referenceMaxSpp < 1) fail("view: the reference needs at least 1 sample per pixel");
  if (scene_.lights.empty()) fail("scene '{}' ({}) has no light; add one to \"lights\"", scene_.name, scene_.source);
  const Bounds3 bounds = scene_.bounds();
  sceneCentre_ = bounds.empty() ? Vec3(0.0f) : bounds.center();
  sceneRadius_ = bounds.empty() ? 1.0f : std::max(bounds.radius(), 1e-3f);
}

ViewSession::~ViewSession() = default;

ViewRequest ViewSession::initialRequest(const std::string& technique, int lightIndex) const {
  if (lightIndex < 0 || lightIndex >= static_cast<int>(scene_.lights.size()))
    fail("--light {} is out of range: scene '{}' has {} light(s)", lightIndex, scene_.name, scene_.lights.size());
  const Light& light = scene_.lights[static_cast<size_t>(lightIndex)];
  ViewRequest request;
  request.camera = scene_.camera;
  request.lightIndex = lightIndex;
  request.shape = light.shape();
  request.lightPosition =
      light.isDirectional() ? sceneCentre_ + 2.0f * sceneRadius_ * light.direction() : light.center();
  request.lightSize = baseSize(light);
  request.technique = technique;
  if (const auto it = scene_.techniqueParams.find(technique); it != scene_.techniqueParams.end())
    for (const auto& [name, entry] : it->second.entries()) request.params[name] = formatParamValue(entry.value);
  return request;
}

std::string ViewSession::setupJson(const std::string& initialTechnique, int initialLight) const {
  json lights = json::array();
  for (int i = 0; i < static_cast<int>(scene_.lights.size()); ++i) {
    const ViewRequest start = initialRequest(initialTechnique, i);
    lights.push_back({{"index", i},
                      {"shape", std::string(toString(start.shape))},
                      {"position", toJson(start.lightPosition)},
                      {"size", start.lightSize}});
  }
  json techniques = json::array();
  for (const TechniqueInfo& info : techniqueRegistry()) {
    if (info.name == "reference") continue;  // the other side of the split view
    json params = json::array();
    for (const ParamSpec& spec : info.params) params.push_back(schemaJson(spec));
    json given = json::object();  // the scene file's values, which the page starts from
    if (const auto it = scene_.techniqueParams.find(info.name); it != scene_.techniqueParams.end())
      for (const auto& [name, entry] : it->second.entries()) given[name] = formatParamValue(entry.value);
    techniques.push_back({{"name", info.name},
                          {"given", given},
                          {"summary", info.summary},
                          {"source", info.source},
                          {"lights", info.lights},
                          {"params", params}});
  }
  json shapes = json::array();
  for (LightShape shape : kShapes) shapes.push_back(std::string(toString(shape)));
  const Camera& camera = scene_.camera;
  const json setup = {{"scene", scene_.name},
                      {"source", scene_.source},
                      {"width", options_.width},
                      {"height", options_.height},
                      {"camera",
                       {{"position", toJson(camera.position)},
                        {"lookAt", toJson(camera.lookAt)},
                        {"up", toJson(camera.up)},
                        {"fovY", camera.fovYDegrees}}},
                      {"centre", toJson(sceneCentre_)},
                      {"radius", sceneRadius_},
                      {"lights", lights},
                      {"shapes", shapes},
                      {"techniques", techniques},
                      {"initial", {{"technique", initialTechnique}, {"light", initialLight}}},
                      {"referenceMaxSpp", options_.referenceMaxSpp},
                      {"encoding", options_.encoding == FrameEncoding::Png ? "png" : "raw"},
                      {"errorRange", kErrorRange}};
  return setup.dump();
}

ViewRequest ViewSession::parseRequest(const std::string& text) const {
  json body;
  try {
    body = json::parse(text);
  } catch (const json::exception& e) {
    fail("request: not JSON ({})", e.what());
  }
  if (!body.is_object()) fail("request: expected a JSON object");
  ViewRequest request;
  const json& camera = readObject(body, "camera", "request");
  request.camera.position = readVec3(camera, "position", "request.camera");
  request.camera.lookAt = readVec3(camera, "lookAt", "request.camera");
  request.camera.up = readVec3(camera, "up", "request.camera");
  request.camera.fovYDegrees = static_cast<float>(readNumber(camera, "fovY", "request.camera"));
  const json& light = readObject(body, "light", "request");
  const double index = readNumber(light, "index", "request.light");
  if (index != std::floor(index) || index < 0 || index >= static_cast<double>(scene_.lights.size()))
    fail("request.light.index: {} is not a light of scene '{}' (it has {})", index, scene_.name, scene_.lights.size());
  request.lightIndex = static_cast<int>(index);
  const std::string shape = readString(light, "shape", "request.light");
  bool known = false;
  std::vector<std::string> names;
  for (LightShape s : kShapes) {
    names.emplace_back(toString(s));
    if (shape == toString(s)) request.shape = s, known = true;
  }
  if (!known) fail("request.light.shape: '{}' is not one of {}", shape, fmt::format("{}", fmt::join(names, ", ")));
  request.lightPosition = readVec3(light, "position", "request.light");
  request.lightSize = static_cast<float>(readNumber(light, "size", "request.light"));
  request.technique = readString(body, "technique", "request");
  if (const auto it = body.find("params"); it != body.end()) {
    if (!it->is_object()) fail("request.params: expected an object of name: value");
    for (const auto& [name, value] : it->items()) {
      if (value.is_string())
        request.params[name] = value.get<std::string>();
      else if (value.is_number() || value.is_boolean())
        request.params[name] = value.dump();
      else
        fail("request.params.{}: expected a number, a boolean or a string", name);
    }
  }
  const std::string display = readString(body, "display", "request");
  if (display == "v")
    request.display = ViewDisplay::Visibility;
  else if (display == "shaded")
    request.display = ViewDisplay::Shaded;
  else if (display == "error")
    request.display = ViewDisplay::Error;
  else
    fail("request.display: '{}' is not one of v, shaded, error", display);
  return request;
}

Light ViewSession::makeLight(const ViewRequest& request) const {
  if (request.lightIndex < 0 || request.lightIndex >= static_cast<int>(scene_.lights.size()))
    fail("light {} is not a light of scene '{}'", request.lightIndex, scene_.name);
  const Light& base = scene_.lights[static_cast<size_t>(request.lightIndex)];
  const float size = request.lightSize;
  const Vec3 p = request.lightPosition;
  const float largest = request.shape == LightShape::Directional ? 90.0f : 100.0f * sceneRadius_;
  if (!(size > 0.0f) || !(size <= largest))
    fail("light size {} is out of range: expected (0, {:g}] {}", size, largest,
         request.shape == LightShape::Directional ? "degrees" : "world units");
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) fail("light position is not finite");
  const ViewRequest start = initialRequest(request.technique, request.lightIndex);
  if (sameLight(start, request)) return base;  // the scene's own light, as the file gives it
  // Planar lights face the scene's centre; a segment lies across the direction to it.
  const Vec3 toCentre = sceneCentre_ - p;
  if (request.shape != LightShape::Sphere && request.shape != LightShape::Polygon && !(glm::length(toCentre) > 1e-6f))
    fail("a {} light at the scene's centre has no direction to face", toString(request.shape));
  Light light = [&] {
    switch (request.shape) {
      case LightShape::Sphere:
        return Light::sphere(p, size);
      case LightShape::Disk:
        return Light::disk(p, glm::normalize(toCentre), size);
      case LightShape::Rect:
      case LightShape::Segment: {
        const Vec3 n = glm::normalize(toCentre);
        const Vec3 helper = std::abs(n.y) < 0.9f ? Vec3(0.0f, 1.0f, 0.0f) : Vec3(1.0f, 0.0f, 0.0f);
        const Vec3 u = glm::normalize(glm::cross(helper, n));
        if (request.shape == LightShape::Segment) return Light::segment(p - size * u, p + size * u);
        return Light::rect(p, size * u, size * glm::normalize(glm::cross(n, u)));
      }
      case LightShape::Polygon: {
        if (base.shape() != LightShape::Polygon)
          fail("a polygon light keeps the scene's polygon, and light {} is a {}: choose another shape",
               request.lightIndex, toString(base.shape()));
        std::vector<Vec3> vertices;
        const float scale = size / base.extent();
        for (const Vec3& v : base.vertices()) vertices.push_back(p + scale * (v - base.center()));
        return Light::polygon(vertices);
      }
      case LightShape::Directional: {
        const Vec3 d = p - sceneCentre_;
        if (!(glm::length(d) > 1e-6f)) fail("a directional light needs a position away from the scene's centre");
        return Light::directional(glm::normalize(d), glm::radians(size),
                                  base.isDirectional() ? base.profile() : LightProfile::Uniform);
      }
    }
    fail("internal: unknown light shape");
  }();
  light.setIntensity(base.intensity());
  return light;
}

ViewFrame ViewSession::render(const ViewRequest& request) {
  ViewFrame frame;
  request.camera.validate();
  const Light light = makeLight(request);
  const TechniqueInfo& info = findTechnique(request.technique);
  if (info.name == "reference")
    fail("request.technique: the reference is the other side of the view; choose a technique");
  ParamSet given;
  for (const auto& [name, value] : request.params) given.set(name, value, "page");
  const Params params = resolveParams(info.name, info.params, given);  // the schema's message for a bad value

  Timer timer;
  const bool cameraMoved = !gbufferCamera_ || !sameCamera(*gbufferCamera_, request.camera);
  if (cameraMoved) {
    scene_.camera = request.camera;
    renderGBuffer(scene_, options_.width, options_.height, gbuffer_);
    gbufferCamera_ = request.camera;
  }
  frame.gbufferCached = !cameraMoved;
  frame.passMs.emplace_back("gbuffer", cameraMoved ? timer.elapsedMs() : 0.0);
  const bool lightMoved = !lightKey_ || !sameLight(*lightKey_, request);
  lightKey_ = request;
  if (cameraMoved || lightMoved) mask_ = errorMask(gbuffer_, light);

  const bool techniqueChanged =
      !technique_ || info.name != techniqueName_ || params.values() != techniqueParams_.values();
  if (techniqueChanged) {
    technique_.reset();
    technique_ = info.create(params);
    // Its frames' storage made now, at the view's size (ShadowTechnique::reserve), as bench and compare
    // do: this frame would otherwise fault it in piecemeal, inside the passes it times.
    technique_->reserve(gbuffer_.width(), gbuffer_.height());
    techniqueName_ = info.name;
    techniqueParams_ = params;
    techniqueValid_ = false;
    techniqueError_.reset();
  }
  double prepareMs = 0.0, visibilityMs = 0.0;
  const bool runTechnique = techniqueChanged || cameraMoved || lightMoved || (!techniqueValid_ && !techniqueError_);
  if (runTechnique) {
    techniqueValid_ = false;
    techniqueError_.reset();
    try {
      timer.reset();
      technique_->prepare(scene_, light);
      prepareMs = timer.elapsedMs();
      timer.reset();
      technique_->visibility(gbuffer_, v_);
      visibilityMs = timer.elapsedMs();
      techniqueValid_ = true;
    } catch (const Error& e) {
      techniqueError_ = e.what();  // this light or scene only: the reference side goes on
    }
  }
  frame.techniqueCached = !runTechnique;
  frame.techniqueError = techniqueError_;
  frame.passMs.emplace_back("prepare", prepareMs);
  frame.passMs.emplace_back("visibility", visibilityMs);

  timer.reset();
  if (cameraMoved || lightMoved) {
    reference_.prepare(scene_, light);
    sumV_.reset(options_.width, options_.height, 0.0);
    sumVariance_.reset(options_.width, options_.height, 0.0);
    referenceSamples_ = referenceBatches_ = lastBatch_ = 0;
  }
  if (referenceSamples_ < options_.referenceMaxSpp) {
    uint32_t spp = lastBatch_ == 0 ? kFirstBatch : std::min(2 * lastBatch_, kLargestBatch);
    spp = std::min(spp, options_.referenceMaxSpp - referenceSamples_);
    ReferenceOptions batch;
    batch.samplesPerPixel = spp;
    batch.seed = referenceBatches_ + 1;  // each batch its own sample patterns
    reference_.setOptions(batch);
    reference_.visibility(gbuffer_, batchV_);
    const Image<float>& stdError = reference_.standardError();
    const double n = spp;
    for (size_t i = 0; i < batchV_.size(); ++i) {
      sumV_[i] += n * batchV_[i];
      sumVariance_[i] += (n * stdError[i]) * (n * stdError[i]);
    }
    referenceSamples_ += spp;
    ++referenceBatches_;
    lastBatch_ = spp;
    referenceV_.reset(options_.width, options_.height, 1.0f);
    for (size_t i = 0; i < sumV_.size(); ++i) referenceV_[i] = static_cast<float>(sumV_[i] / referenceSamples_);
  }
  frame.passMs.emplace_back("reference", timer.elapsedMs());
  frame.referenceSamples = referenceSamples_;
  frame.referenceMaxSamples = options_.referenceMaxSpp;

  timer.reset();
  double errorSum = 0.0;
  size_t masked = 0;
  for (size_t i = 0; i < mask_.size(); ++i)
    if (mask_[i]) {
      errorSum += std::sqrt(sumVariance_[i]) / referenceSamples_;
      ++masked;
    }
  frame.referenceStdError = masked ? errorSum / static_cast<double>(masked) : 0.0;
  if (techniqueValid_) frame.error = compareVisibility(v_, referenceV_, mask_);
  frame.passMs.emplace_back("metrics", timer.elapsedMs());

  timer.reset();
  const int w = options_.width, h = options_.height;
  const FrameEncoding encoding = options_.encoding;
  frame.display = request.display;
  switch (request.display) {
    case ViewDisplay::Visibility:
      if (techniqueValid_) frame.technique = makeImage(w, h, 1, grayBytes(v_), encoding);
      frame.reference = makeImage(w, h, 1, grayBytes(referenceV_), encoding);
      break;
    case ViewDisplay::Shaded:
      if (techniqueValid_)
        frame.technique = makeImage(w, h, 3, srgbBytes(shade(scene_, light, gbuffer_, v_)), encoding);
      frame.reference = makeImage(w, h, 3, srgbBytes(shade(scene_, light, gbuffer_, referenceV_)), encoding);
      break;
    case ViewDisplay::Error:
      if (techniqueValid_)
        frame.technique = makeImage(w, h, 3, srgbBytes(signedErrorMap(v_, referenceV_, mask_, kErrorRange)), encoding);
      frame.reference = makeImage(w, h, 1, grayBytes(referenceV_), encoding);
      break;
  }
  frame.passMs.emplace_back("encode", timer.elapsedMs());
  return frame;
}

std::string encodeViewFrame(const ViewFrame& frame) {
  json passes = json::array();
  for (const auto& [pass, ms] : frame.passMs) passes.push_back(json::array({pass, ms}));
  const char* display = frame.display == ViewDisplay::Shaded  ? "shaded"
                        : frame.display == ViewDisplay::Error ? "error"
                                                              : "v";
  json header = {{"passes", passes},
                 {"display", display},
                 {"gbufferCached", frame.gbufferCached},
                 {"techniqueCached", frame.techniqueCached},
                 {"reference",
                  {{"samples", frame.referenceSamples},
                   {"maxSamples", frame.referenceMaxSamples},
                   {"stdError", frame.referenceStdError}}}};
  header["techniqueError"] = frame.techniqueError ? json(*frame.techniqueError) : json(nullptr);
  if (frame.error)
    header["error"] = {{"rmse8", frame.error->rmse8},           {"penumbraRmse8", frame.error->penumbraRmse8},
                       {"umbraLeaks", frame.error->umbraLeaks}, {"speckle", frame.error->speckle},
                       {"maskPixels", frame.error->maskPixels}, {"penumbraPixels", frame.error->penumbraPixels}};
  else
    header["error"] = nullptr;
  json images = json::array();
  size_t offset = 0;
  const auto describe = [&](const char* side, const ViewImage& image) {
    images.push_back({{"side", side},
                      {"offset", offset},
                      {"length", image.bytes.size()},
                      {"width", image.width},
                      {"height", image.height},
                      {"channels", image.channels},
                      {"format", image.png ? "png" : "raw"}});
    offset += image.bytes.size();
  };
  if (frame.technique) describe("technique", *frame.technique);
  describe("reference", frame.reference);
  header["images"] = images;
  const std::string text = header.dump();
  std::string out;
  out.reserve(4 + text.size() + offset);
  const auto length = static_cast<uint32_t>(text.size());
  for (int byte = 0; byte < 4; ++byte) out.push_back(static_cast<char>((length >> (8 * byte)) & 0xffu));
  out += text;
  const auto append = [&](const ViewImage& image) {
    out.append(reinterpret_cast<const char*>(image.bytes.data()), image.bytes.size());
  };
  if (frame.technique) append(*frame.technique);
  append(frame.reference);
  return out;
}

}  // namespace penumbra::cli
