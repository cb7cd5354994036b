// The JSON scene format (docs/scene-format.md) and the built-in scenes (scenes/*.json, compiled in
// by cmake/embed_scenes.cmake).
//
// The reader is strict, because a silently ignored or defaulted field corrupts a comparison:
// unknown keys, duplicate keys, wrong types, wrong array lengths, non-finite or out-of-range values,
// missing required fields, duplicate object ids and degenerate lights are all errors, and every
// message reads "<file>: <field path>: <what was expected>" (for example
// "scenes/x.json: objects[2].transform.rotate: expected an array of 3 numbers").
// Numbers are stored as float; a JSON number outside float range is an error, not an infinity.
// Angles in the file are degrees; lengths are world units (y up by convention, not by requirement).
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/ranges.h>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/scene_io.h"

namespace penumbra {

namespace detail {
// Generated from scenes/*.json (cmake/embed_scenes.cmake): (file stem, JSON text), sorted by stem.
const std::vector<std::pair<std::string_view, std::string_view>>& embeddedScenes();
}  // namespace detail

namespace {

using json = nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Reading helpers: every value is read through a Field, which knows where it is for messages.

class Field {
 public:
  Field(const json& value, std::string path, const std::string& source)
      : value_(value), path_(std::move(path)), source_(source) {}

  const json& value() const { return value_; }
  const std::string& path() const { return path_; }
  const std::string& source() const { return source_; }

  template <class... Args>
  [[noreturn]] void error(fmt::format_string<Args...> format, Args&&... args) const {
    fail("{}: {}: {}", source_, path_, fmt::format(format, std::forward<Args>(args)...));
  }

  Field child(const std::string& key) const {
    return Field(value_.at(key), path_.empty() ? key : path_ + "." + key, source_);
  }
  Field element(size_t i) const { return Field(value_.at(i), fmt::format("{}[{}]", path_, i), source_); }

  float number() const {
    if (!value_.is_number()) error("expected a number, got {}", describe());
    const double d = value_.get<double>();
    const float f = static_cast<float>(d);
    if (!std::isfinite(f)) error("expected a finite number within float range, got {}", value_.dump());
    return f;
  }
  float positive() const {
    const float f = number();
    if (!(f > 0.0f)) error("expected a number > 0, got {}", value_.dump());
    return f;
  }
  float nonNegative() const {
    const float f = number();
    if (!(f >= 0.0f)) error("expected a number >= 0, got {}", value_.dump());
    return f;
  }
  int integer(int minimum, int maximum) const {
    if (!value_.is_number_integer()) error("expected an integer in [{}, {}], got {}", minimum, maximum, describe());
    const int64_t i = value_.get<int64_t>();
    if (i < minimum || i > maximum) error("expected an integer in [{}, {}], got {}", minimum, maximum, i);
    return static_cast<int>(i);
  }
  std::string string() const {
    if (!value_.is_string()) error("expected a string, got {}", describe());
    return value_.get<std::string>();
  }
  Vec3 vec3() const {
    if (!value_.is_array() || value_.size() != 3) error("expected an array of 3 numbers, got {}", describe());
    Vec3 v;
    for (int k = 0; k < 3; ++k) {
      if (!value_[k].is_number()) error("expected an array of 3 numbers, got {}", describe());
      v[k] = element(k).number();
    }
    return v;
  }
  const json& array(size_t minSize, const char* what) const {
    if (!value_.is_array() || value_.size() < minSize)
      error("expected an array of {}{}, got {}", minSize > 0 ? fmt::format("at least {} ", minSize) : "", what,
            describe());
    return value_;
  }

  std::string describe() const {
    std::string text = value_.dump();
    if (text.size() > 40) text = text.substr(0, 37) + "...";
    switch (value_.type()) {
      case json::value_t::array:
        return fmt::format("an array of {} ({})", value_.size(), text);
      case json::value_t::object:
        return "an object";
      case json::value_t::null:
        return "null";
      case json::value_t::boolean:
        return fmt::format("a boolean ({})", text);
      case json::value_t::string:
        return fmt::format("a string ({})", text);
      default:
        return fmt::format("a number ({})", text);
    }
  }

 private:
  const json& value_;
  std::string path_;
  const std::string& source_;
};

size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// A JSON object with a fixed set of keys: rejects unknown keys (suggesting the nearest known one)
// and reports missing required ones.
class ObjectField {
 public:
  ObjectField(const Field& field, std::vector<std::string> known) : field_(field), known_(std::move(known)) {
    if (!field.value().is_object()) field.error("expected an object, got {}", field.describe());
    for (const auto& [key, value] : field.value().items()) {
      if (std::find(known_.begin(), known_.end(), key) != known_.end()) continue;
      std::string hint;
      size_t best = 3;
      for (const std::string& k : known_)
        if (const size_t d = editDistance(key, k); d < best) {
          best = d;
          hint = fmt::format(" (did you mean '{}'?)", k);
        }
      field.error("unknown key '{}'{}; expected one of: {}", key, hint, fmt::join(known_, ", "));
    }
  }
  bool has(const std::string& key) const { return field_.value().contains(key); }
  Field required(const std::string& key) const {
    if (!has(key)) field_.error("missing required key '{}'", key);
    return field_.child(key);
  }
  std::optional<Field> optional(const std::string& key) const {
    if (!has(key)) return std::nullopt;
    return field_.child(key);
  }
  const Field& field() const { return field_; }

 private:
  const Field& field_;
  std::vector<std::string> known_;
};

// Runs `make` and prefixes any Error it throws with the file and field path, dropping the
// component's own prefix ("light: ", "camera: ") which the path already says better.
template <class F>
auto withPath(const Field& field, F&& make) {
  try {
    return make();
  } catch (const Error& e) {
    std::string message = e.what();
    for (std::string_view prefix : {"light: ", "camera: "})
      if (message.rfind(prefix, 0) == 0) message = message.substr(prefix.size());
    field.error("{}", message);
  }
}

// ---------------------------------------------------------------------------------------------
// Strict JSON parsing: line and column for syntax errors, and duplicate keys rejected (nlohmann
// would keep the last one silently).

std::pair<size_t, size_t> lineColumn(const std::string& text, size_t byte) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

json parseJson(const std::string& text, const std::string& source) {
  struct Frame {
    bool isArray = false;
    size_t index = 0;
    std::string key;
    std::set<std::string> keys;
  };
  std::vector<Frame> stack;
  const auto pathTo = [&](const std::string& last) {
    std::string path;
    for (size_t i = 0; i + 1 < stack.size(); ++i) {
      const Frame& f = stack[i];
      if (f.isArray)
        path += fmt::format("[{}]", f.index);
      else
        path += (path.empty() ? "" : ".") + f.key;
    }
    return path.empty() ? last : path + "." + last;
  };
  const auto elementDone = [&] {
    if (!stack.empty() && stack.back().isArray) ++stack.back().index;
  };
  json::parser_callback_t callback = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        stack.push_back(Frame{});
        break;
      case json::parse_event_t::array_start:
        stack.push_back(Frame{});
        stack.back().isArray = true;
        break;
      case json::parse_event_t::key: {
        const std::string key = parsed.get<std::string>();
        Frame& top = stack.back();
        if (!top.keys.insert(key).second)
          fail("{}: {}: duplicate key '{}'; each key may appear once", source, pathTo(key), key);
        top.key = key;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        elementDone();
        break;
      case json::parse_event_t::value:
        elementDone();
        break;
    }
    return true;
  };
  try {
    return json::parse(text, callback);
  } catch (const json::parse_error& e) {
    const auto [line, column] = lineColumn(text, e.byte);
    std::string detail = e.what();
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line L, column C: <detail>".
    if (const size_t at = detail.find("column"); at != std::string::npos)
      if (const size_t colon = detail.find(": ", at); colon != std::string::npos) detail = detail.substr(colon + 2);
    fail("{}: malformed JSON at line {}, column {}: {}", source, line, column, detail);
  } catch (const json::out_of_range& e) {
    // A number literal too large for a double ("1e999"); nlohmann names it but not where it is.
    std::string detail = e.what();
    if (const size_t bracket = detail.find("] "); bracket != std::string::npos) detail = detail.substr(bracket + 2);
    std::string path;
    for (const Frame& f : stack) {
      if (f.isArray)
        path += fmt::format("[{}]", f.index);
      else if (!f.key.empty())
        path += (path.empty() ? "" : ".") + f.key;
    }
    fail("{}: {}: {}; expected a number within the range of a double", source, path.empty() ? "JSON" : path, detail);
  }
}

// ---------------------------------------------------------------------------------------------
// Scene parts.

Camera readCamera(const Field& field) {
  const ObjectField o(field, {"position", "look_at", "up", "fov_y"});
  Camera camera;
  camera.position = o.required("position").vec3();
  camera.lookAt = o.required("look_at").vec3();
  if (auto up = o.optional("up")) camera.up = up->vec3();
  if (auto fov = o.optional("fov_y")) camera.fovYDegrees = fov->number();
  withPath(field, [&] {
    camera.validate();
    return 0;
  });
  return camera;
}

// "motion": {"moves": "light" | "camera", "light": index, "path": [[x, y, z], ...], "frames": N}
// (include/penumbra/motion.h); validated against the scene's lights and camera.
Motion readMotion(const Field& field, const Scene& scene) {
  const ObjectField o(field, {"moves", "light", "path", "frames"});
  Motion motion;
  const std::string moves = o.required("moves").string();
  if (moves == "light") {
    motion.target = MotionTarget::Light;
  } else if (moves == "camera") {
    motion.target = MotionTarget::Camera;
    if (auto light = o.optional("light"))
      light->error("a light index is for \"moves\": \"light\"; the camera moves here");
  } else {
    o.required("moves").error("expected \"light\" or \"camera\", got \"{}\"", moves);
  }
  if (auto light = o.optional("light"))
    motion.lightIndex = light->integer(0, std::max(0, static_cast<int>(scene.lights.size()) - 1));
  const Field path = o.required("path");
  path.array(2, "key points [x, y, z]");
  for (size_t i = 0; i < path.value().size(); ++i) motion.path.push_back(path.element(i).vec3());
  if (auto frames = o.optional("frames")) motion.frames = frames->integer(2, kMaxMotionFrames);
  motion.validate(scene, fmt::format("{}: {}", field.source(), field.path()));
  return motion;
}

Light readLight(const Field& field) {
  if (!field.value().is_object()) field.error("expected a light object, got {}", field.describe());
  if (!field.value().contains("type"))
    field.error("missing required key 'type' (one of sphere, disk, rect, segment, polygon, directional)");
  const std::string type = field.child("type").string();
  const auto keys = [&](std::initializer_list<const char*> shapeKeys) {
    std::vector<std::string> k{"type", "intensity"};
    k.insert(k.end(), shapeKeys.begin(), shapeKeys.end());
    return k;
  };
  std::optional<Light> light;
  std::optional<ObjectField> o;
  if (type == "sphere") {
    o.emplace(field, keys({"center", "radius"}));
    const Vec3 center = o->required("center").vec3();
    const float radius = o->required("radius").positive();
    light = withPath(field, [&] { return Light::sphere(center, radius); });
  } else if (type == "disk") {
    o.emplace(field, keys({"center", "normal", "radius"}));
    const Vec3 center = o->required("center").vec3();
    const Vec3 normal = o->required("normal").vec3();
    const float radius = o->required("radius").positive();
    light = withPath(o->field().child("normal"), [&] { return Light::disk(center, normal, radius); });
  } else if (type == "rect") {
    o.emplace(field, keys({"center", "u", "v"}));
    const Vec3 center = o->required("center").vec3();
    const Vec3 u = o->required("u").vec3();
    const Vec3 v = o->required("v").vec3();
    light = withPath(field, [&] { return Light::rect(center, u, v); });
  } else if (type == "segment") {
    o.emplace(field, keys({"a", "b"}));
    const Vec3 a = o->required("a").vec3();
    const Vec3 b = o->required("b").vec3();
    light = withPath(field, [&] { return Light::segment(a, b); });
  } else if (type == "polygon") {
    o.emplace(field, keys({"vertices"}));
    const Field vs = o->required("vertices");
    vs.array(3, "[x, y, z] vertices (a planar simple polygon, convex or concave, in order)");
    std::vector<Vec3> vertices;
    for (size_t i = 0; i < vs.value().size(); ++i) vertices.push_back(vs.element(i).vec3());
    light = withPath(vs, [&] { return Light::polygon(vertices); });
  } else if (type == "directional") {
    o.emplace(field, keys({"direction", "angular_diameter", "profile"}));
    const Vec3 direction = o->required("direction").vec3();
    const Field diameter = o->required("angular_diameter");
    const float degreesValue = diameter.number();
    if (!(degreesValue > 0.0f && degreesValue < 180.0f))
      diameter.error("expected an angle in (0, 180) degrees, got {}", degreesValue);
    LightProfile profile = LightProfile::Uniform;
    if (auto p = o->optional("profile")) {
      const std::string name = p->string();
      if (name == "limb-darkened")
        profile = LightProfile::LimbDarkened;
      else if (name != "uniform")
        p->error("expected \"uniform\" or \"limb-darkened\", got \"{}\"", name);
    }
    light = withPath(o->field().child("direction"),
                     [&] { return Light::directional(direction, radians(degreesValue), profile); });
  } else {
    field.child("type").error(
        "unknown light type \"{}\"; expected one of sphere, disk, rect, segment, polygon, directional", type);
  }
  if (auto intensity = o->optional("intensity")) light->setIntensity(intensity->nonNegative());
  return *light;
}

Mesh readPrimitive(const Field& field) {
  if (!field.value().is_object()) field.error("expected an object with a \"type\", got {}", field.describe());
  if (!field.value().contains("type"))
    field.error("missing required key 'type' (one of plane, box, sphere, torus, cylinder, triangle)");
  const std::string type = field.child("type").string();
  const auto optionalInt = [](const ObjectField& o, const char* key, int fallback, int minimum) {
    auto f = o.optional(key);
    return f ? f->integer(minimum, 1 << 16) : fallback;
  };
  // A size given as one number (a cube, a square) or per axis.
  const auto sizes = [](const Field& f, int n) {
    Vec3 s(0.0f);
    if (f.value().is_number()) return Vec3(f.positive());
    if (!f.value().is_array() || f.value().size() != static_cast<size_t>(n))
      f.error("expected a number > 0 or an array of {} numbers > 0, got {}", n, f.describe());
    for (int k = 0; k < n; ++k) s[k] = f.element(k).positive();
    return s;
  };
  const auto make = [&](auto&& build) { return withPath(field, build); };
  if (type == "plane") {
    const ObjectField o(field, {"type", "size"});
    const Vec3 s = sizes(o.required("size"), 2);
    return make([&] { return makePlane(s.x, s.y); });
  }
  if (type == "box") {
    const ObjectField o(field, {"type", "size"});
    const Vec3 s = sizes(o.required("size"), 3);
    return make([&] { return makeBox(s); });
  }
  if (type == "sphere") {
    const ObjectField o(field, {"type", "radius", "segments", "rings"});
    const float radius = o.required("radius").positive();
    const int segments = optionalInt(o, "segments", 48, 3);
    const int rings = optionalInt(o, "rings", 24, 2);
    return make([&] { return makeSphere(radius, segments, rings); });
  }
  if (type == "torus") {
    const ObjectField o(field, {"type", "major_radius", "minor_radius", "major_segments", "minor_segments"});
    const float major = o.required("major_radius").positive();
    const Field minorField = o.required("minor_radius");
    const float minor = minorField.positive();
    if (!(minor < major)) minorField.error("expected a number smaller than major_radius ({}), got {}", major, minor);
    const int majorSegments = optionalInt(o, "major_segments", 64, 3);
    const int minorSegments = optionalInt(o, "minor_segments", 32, 3);
    return make([&] { return makeTorus(major, minor, majorSegments, minorSegments); });
  }
  if (type == "cylinder") {
    const ObjectField o(field, {"type", "radius", "height", "segments"});
    const float radius = o.required("radius").positive();
    const float height = o.required("height").positive();
    const int segments = optionalInt(o, "segments", 48, 3);
    return make([&] { return makeCylinder(radius, height, segments); });
  }
  if (type == "triangle") {
    const ObjectField o(field, {"type", "vertices"});
    const Field vs = o.required("vertices");
    if (!vs.value().is_array() || vs.value().size() != 3)
      vs.error("expected an array of 3 [x, y, z] vertices, got {}", vs.describe());
    const Vec3 a = vs.element(0).vec3(), b = vs.element(1).vec3(), c = vs.element(2).vec3();
    return withPath(vs, [&] { return makeTriangle(a, b, c); });
  }
  field.child("type").error(
      "unknown primitive type \"{}\"; expected one of plane, box, sphere, torus, cylinder, triangle", type);
}

Mesh readInlineMesh(const Field& field) {
  const ObjectField o(field, {"positions", "triangles", "normals"});
  Mesh mesh;
  const Field positions = o.required("positions");
  positions.array(3, "[x, y, z] positions");
  mesh.positions.reserve(positions.value().size());
  for (size_t i = 0; i < positions.value().size(); ++i) mesh.positions.push_back(positions.element(i).vec3());

  const Field triangles = o.required("triangles");
  triangles.array(1, "[i, j, k] vertex index triples");
  const int maxIndex = static_cast<int>(std::min<size_t>(mesh.positions.size() - 1, 0x7fffffff));
  mesh.triangles.reserve(triangles.value().size());
  for (size_t i = 0; i < triangles.value().size(); ++i) {
    const Field t = triangles.element(i);
    if (!t.value().is_array() || t.value().size() != 3)
      t.error("expected an array of 3 vertex indices, got {}", t.describe());
    glm::uvec3 tri;
    for (int k = 0; k < 3; ++k) tri[k] = static_cast<uint32_t>(t.element(k).integer(0, maxIndex));
    if (tri.x == tri.y || tri.y == tri.z || tri.x == tri.z)
      t.error("expected 3 distinct vertex indices, got [{}, {}, {}]", tri.x, tri.y, tri.z);
    mesh.triangles.push_back(tri);
  }

  if (auto normals = o.optional("normals")) {
    normals->array(0, "[x, y, z] unit normals");
    if (normals->value().size() != mesh.positions.size())
      normals->error("expected one normal per position ({}), got {}", mesh.positions.size(), normals->value().size());
    mesh.normals.reserve(mesh.positions.size());
    for (size_t i = 0; i < normals->value().size(); ++i) {
      const Field n = normals->element(i);
      const Vec3 v = n.vec3();
      // Unit length is required, not enforced by normalizing, so a file reads back bit for bit.
      if (!(std::abs(glm::length(v) - 1.0f) < 1e-3f)) n.error("expected a unit vector, got length {}", glm::length(v));
      mesh.normals.push_back(v);
    }
  }
  return mesh;
}

Mat4 readTransform(const Field& field) {
  const ObjectField o(field, {"translate", "rotate", "scale"});
  Vec3 scale(1.0f);
  if (auto s = o.optional("scale")) {
    if (s->value().is_number()) {
      scale = Vec3(s->number());
    } else {
      if (!s->value().is_array() || s->value().size() != 3)
        s->error("expected a number or an array of 3 numbers, got {}", s->describe());
      scale = s->vec3();
    }
    if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
      s->error("expected non-zero scale factors (a zero flattens the object)");
  }
  Mat4 m(1.0f);
  if (auto t = o.optional("translate")) m = glm::translate(m, t->vec3());
  if (auto r = o.optional("rotate")) {
    const Vec3 angles = r->vec3();
    // Applied about x, then y, then z (fixed world axes): R = Rz Ry Rx.
    m = glm::rotate(m, radians(angles.z), Vec3(0, 0, 1));
    m = glm::rotate(m, radians(angles.y), Vec3(0, 1, 0));
    m = glm::rotate(m, radians(angles.x), Vec3(1, 0, 0));
  }
  return glm::scale(m, scale);
}

Mat4 readMatrix(const Field& field) {
  const auto bad = [&] {
    field.error("expected 4 rows of 4 numbers (row-major, last row [0, 0, 0, 1]), got {}", field.describe());
  };
  if (!field.value().is_array() || field.value().size() != 4) bad();
  Mat4 m(1.0f);
  for (int row = 0; row < 4; ++row) {
    const Field r = field.element(row);
    if (!r.value().is_array() || r.value().size() != 4) r.error("expected an array of 4 numbers, got {}", r.describe());
    for (int col = 0; col < 4; ++col) m[col][row] = r.element(col).number();  // glm is column-major
  }
  if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f)
    field.element(3).error("expected [0, 0, 0, 1] (an affine transform; projective matrices are not supported)");
  const float det = glm::determinant(Mat3(m));
  if (!(std::abs(det) > 0.0f) || !std::isfinite(det))
    field.error("expected an invertible matrix, got determinant {}", det);
  return m;
}

// The world-space sphere that a centred sphere of `radius` becomes under wsFromObject, or
// nothing when the transform shears or scales it unevenly (the object is then only a mesh).
std::optional<AnalyticSphere> analyticSphere(float radius, const Mat4& wsFromObject) {
  const Mat3 m(wsFromObject);
  const float scale = glm::length(m[0]);
  // Relative tolerance of a few float ulps of a rotation's entries (glm::rotate rounds them).
  const float tolerance = 1e-5f * scale;
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(glm::length(m[i]) - scale) <= tolerance)) return std::nullopt;
    if (!(std::abs(glm::dot(m[i], m[(i + 1) % 3])) <= tolerance * scale)) return std::nullopt;
  }
  return AnalyticSphere{Vec3(wsFromObject[3]), radius * scale};
}

// Coordinates the ray tracer accepts (Embree refuses rays beyond about 1.8e18; squared distances
// between such points still fit a float).
constexpr float kMaxWorldCoordinate = 1e18f;

void checkWorldReach(const Field& field, float reach, const char* what) {
  if (!(reach <= kMaxWorldCoordinate))
    field.error("expected world coordinates within +-{:g} (the ray tracer's limit), but {} reaches {:g}",
                kMaxWorldCoordinate, what, reach);
}

// `fit`: the uniform scale and translation that give the (already transformed) mesh a bounding box
// whose largest side is `size` and whose bottom face (lowest y) is centred on `base`. Models come in
// every unit and origin; this sets one on a ground plane without knowing either.
Mat4 readFit(const Field& field, const Mesh& mesh) {
  const ObjectField o(field, {"size", "base"});
  const float size = o.required("size").positive();
  const Vec3 base = o.has("base") ? o.required("base").vec3() : Vec3(0.0f);
  const Bounds3 bounds = mesh.bounds();
  const Vec3 lo = bounds.lower, hi = bounds.upper;
  const Vec3 extent = hi - lo;
  const float largest = std::max({extent.x, extent.y, extent.z});
  if (!(largest > 0.0f) || !std::isfinite(largest))
    field.error(
        "expected an object with a non-zero, finite extent to fit, got a bounding box from ({}, {}, {}) to ({}, {}, "
        "{})",
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
  const float scale = size / largest;
  const Vec3 bottomCentre(0.5f * (lo.x + hi.x), lo.y, 0.5f * (lo.z + hi.z));
  Mat4 m = glm::translate(Mat4(1.0f), base);
  m = glm::scale(m, Vec3(scale));
  return glm::translate(m, -bottomCentre);
}

// `inputFiles` gains the mesh file the object reads, if any.
Object readObject(const Field& field, size_t index, const std::string& baseDir, std::vector<std::string>& inputFiles,
                  const SceneLoadOptions& options) {
  const ObjectField o(
      field, {"name", "id", "albedo", "primitive", "mesh", "inline", "transform", "matrix", "fit", "analytic_sphere"});
  Object object;
  object.name = o.required("name").string();
  object.id = o.has("id") ? o.required("id").integer(0, 0x7fffffff) : static_cast<int32_t>(index);
  if (auto albedo = o.optional("albedo")) {
    if (!albedo->value().is_number() && !(albedo->value().is_array() && albedo->value().size() == 3))
      albedo->error("expected a number or an array of 3 numbers (r, g, b) in [0, 1], got {}", albedo->describe());
    const Vec3 a = albedo->value().is_number() ? Vec3(albedo->number()) : albedo->vec3();
    if (glm::any(glm::lessThan(a, Vec3(0.0f))) || glm::any(glm::greaterThan(a, Vec3(1.0f))))
      albedo->error("expected reflectances in [0, 1], got [{}, {}, {}]", a.x, a.y, a.z);
    object.albedo = a;
  }

  const int shapes = int(o.has("primitive")) + int(o.has("mesh")) + int(o.has("inline"));
  if (shapes != 1)
    field.error("expected exactly one of 'primitive', 'mesh' or 'inline' (the object's geometry), got {}", shapes);
  if (auto p = o.optional("primitive")) {
    object.mesh = readPrimitive(*p);
  } else if (auto m = o.optional("mesh")) {
    const std::string file = m->string();
    if (file.empty()) m->error("expected a mesh file path, got an empty string");
    std::filesystem::path path(file);
    if (path.is_relative()) path = std::filesystem::path(baseDir) / path;
    inputFiles.push_back(path.lexically_normal().string());
    object.mesh = withPath(*m, [&] { return importMesh(inputFiles.back(), options.maxMeshBytes); });
  } else {
    object.mesh = readInlineMesh(o.required("inline"));
  }

  if (o.has("transform") && o.has("matrix")) field.error("expected at most one of 'transform' and 'matrix', got both");
  Mat4 wsFromObject(1.0f);
  if (auto t = o.optional("transform"))
    withPath(*t, [&] { return transformMesh(object.mesh, wsFromObject = readTransform(*t)), 0; });
  if (auto m = o.optional("matrix"))
    withPath(*m, [&] { return transformMesh(object.mesh, wsFromObject = readMatrix(*m)), 0; });
  if (auto f = o.optional("fit")) {
    const Mat4 fit = readFit(*f, object.mesh);
    transformMesh(object.mesh, fit);
    wsFromObject = fit * wsFromObject;
  }
  const Bounds3 bounds = object.mesh.bounds();
  const Vec3 reach = glm::max(glm::abs(bounds.lower), glm::abs(bounds.upper));
  checkWorldReach(field, std::max({reach.x, reach.y, reach.z}), "the object (after its transform)");
  // A sphere primitive stays a true sphere under rotation, uniform scale and translation.
  if (auto p = o.optional("primitive"); p && p->value().at("type") == "sphere")
    object.sphere = analyticSphere(p->child("radius").number(), wsFromObject);
  if (auto a = o.optional("analytic_sphere")) {
    // Written by sceneToJson next to the inline tessellation, in world space.
    if (!o.has("inline") || o.has("transform") || o.has("matrix") || o.has("fit"))
      a->error(
          "expected only on an object with 'inline' geometry and no 'transform' or 'matrix' (it is in world "
          "space, as sceneToJson writes it); for a new sphere use \"primitive\": {{\"type\": \"sphere\"}}");
    const ObjectField ao(*a, {"center", "radius"});
    object.sphere = AnalyticSphere{ao.required("center").vec3(), ao.required("radius").positive()};
  }
  return object;
}

ParamValue readParamValue(const Field& field) {
  const json& v = field.value();
  if (v.is_boolean()) return v.get<bool>();
  if (v.is_number_integer()) return v.get<int64_t>();
  if (v.is_number_float()) return v.get<double>();
  if (v.is_string()) return v.get<std::string>();
  field.error("expected a number, a boolean or a string, got {}", field.describe());
}

// ---------------------------------------------------------------------------------------------
// Writing: floats as the shortest decimal that reads back to the same float.

json floatJson(float f) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), f);
  const double shortest = std::strtod(std::string(buffer, end).c_str(), nullptr);
  // Reading goes decimal -> double -> float; fall back to the exact double if that rounds twice.
  return ec == std::errc() && static_cast<float>(shortest) == f ? shortest : static_cast<double>(f);
}

json vec3Json(const Vec3& v) { return json::array({floatJson(v.x), floatJson(v.y), floatJson(v.z)}); }

// Lights keep unit vectors and radians, derived from what the file gave; writing them back as is
// can read back one ulp off after normalizing or converting again. These search the few floats
// next to the value for one that the reader maps back exactly; the value itself is kept if none does.
Vec3 exactUnitVector(const Vec3& n, const std::function<Vec3(const Vec3&)>& read) {
  if (read(n) == n) return n;
  // Neighbours of n and of multiples of it: a different length rounds differently. Measured: every
  // one of 1000 random directions finds an exact preimage (SceneToJson tests).
  for (int i = 0; i < 256; ++i)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          Vec3 w = (1.0f + static_cast<float>(i) / 64.0f) * n;
          const int d[3] = {dx, dy, dz};
          for (int k = 0; k < 3; ++k)
            if (d[k] != 0) w[k] = std::nextafter(w[k], d[k] > 0 ? kInfinity : -kInfinity);
          if (read(w) == n) return w;
        }
  return n;
}

float exactDegrees(float angleRadians) {
  float d = degrees(angleRadians);
  for (int i = 0; i < 16 && radians(d) != angleRadians; ++i)
    d = std::nextafter(d, radians(d) < angleRadians ? kInfinity : -kInfinity);
  return radians(d) == angleRadians ? d : degrees(angleRadians);
}

json lightJson(const Light& light) {
  json j;
  j["type"] = std::string(toString(light.shape()));
  switch (light.shape()) {
    case LightShape::Sphere:
      j["center"] = vec3Json(light.center());
      j["radius"] = floatJson(light.radius());
      break;
    case LightShape::Disk:
      j["center"] = vec3Json(light.center());
      j["normal"] = vec3Json(exactUnitVector(
          light.normal(), [&](const Vec3& w) { return Light::disk(light.center(), w, light.radius()).normal(); }));
      j["radius"] = floatJson(light.radius());
      break;
    case LightShape::Rect:
      j["center"] = vec3Json(light.center());
      j["u"] = vec3Json(light.u());
      j["v"] = vec3Json(light.v());
      break;
    case LightShape::Segment:
      j["a"] = vec3Json(light.a());
      j["b"] = vec3Json(light.b());
      break;
    case LightShape::Polygon: {
      json vs = json::array();
      for (const Vec3& v : light.vertices()) vs.push_back(vec3Json(v));
      j["vertices"] = vs;
      break;
    }
    case LightShape::Directional:
      j["direction"] = vec3Json(exactUnitVector(light.direction(), [&](const Vec3& w) {
        return Light::directional(w, light.angularDiameter(), light.profile()).direction();
      }));
      j["angular_diameter"] = floatJson(exactDegrees(light.angularDiameter()));
      j["profile"] = std::string(toString(light.profile()));
      break;
  }
  j["intensity"] = floatJson(light.intensity());
  return j;
}

json paramJson(const ParamValue& value) {
  return std::visit([](const auto& v) { return json(v); }, value);
}

std::string readFileText(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail("{}: not a readable file", path);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open the scene file", path);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) fail("{}: error while reading the scene file", path);
  return text.str();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

Scene parseScene(const std::string& jsonText, const std::string& source, const std::string& baseDir,
                 const SceneLoadOptions& options) {
  const json root = parseJson(jsonText, source);
  const Field rootField(root, "", source);
  if (!root.is_object()) fail("{}: expected a JSON object at the top level, got {}", source, rootField.describe());
  const ObjectField o(
      rootField, {"name", "description", "image", "camera", "ambient", "lights", "objects", "techniques", "motion"});

  Scene scene;
  scene.source = source;
  if (auto name = o.optional("name")) {
    scene.name = name->string();
    if (scene.name.empty()) name->error("expected a non-empty name");
  } else {
    scene.name = std::filesystem::path(source).stem().string();
  }
  if (auto description = o.optional("description")) description->string();

  if (auto image = o.optional("image")) {
    const ObjectField io(*image, {"width", "height"});
    scene.image.width = io.required("width").integer(1, kMaxImageSide);
    scene.image.height = io.required("height").integer(1, kMaxImageSide);
    checkImageSize(scene.image.width, scene.image.height, source + ": image");
  }
  scene.camera = readCamera(o.required("camera"));
  if (auto ambient = o.optional("ambient")) scene.ambient = ambient->nonNegative();

  const Field lights = o.required("lights");
  lights.array(0, "lights");
  for (size_t i = 0; i < lights.value().size(); ++i) {
    scene.lights.push_back(readLight(lights.element(i)));
    const Light& light = scene.lights.back();
    if (!light.isDirectional()) {
      const Vec3 reach = glm::abs(light.center()) + Vec3(light.extent());
      checkWorldReach(lights.element(i), std::max({reach.x, reach.y, reach.z}), "the light");
    }
  }

  const Field objects = o.required("objects");
  objects.array(0, "objects");
  std::map<int32_t, size_t> idToIndex;
  for (size_t i = 0; i < objects.value().size(); ++i) {
    const Field f = objects.element(i);
    Object object = readObject(f, i, baseDir, scene.inputFiles, options);
    if (auto [it, inserted] = idToIndex.emplace(object.id, i); !inserted)
      f.error(
          "duplicate object id {} (objects[{}] has it too; an object without 'id' takes its index); expected unique "
          "ids",
          object.id, it->second);
    scene.objects.push_back(std::move(object));
  }

  if (auto motion = o.optional("motion")) scene.motion = readMotion(*motion, scene);

  if (auto techniques = o.optional("techniques")) {
    if (!techniques->value().is_object())
      techniques->error("expected an object {{\"<technique>\": {{\"<parameter>\": value}}}}, got {}",
                        techniques->describe());
    for (const auto& [technique, params] : techniques->value().items()) {
      const Field tf = techniques->child(technique);
      if (!params.is_object())
        tf.error("expected an object of parameters {{\"<parameter>\": value}}, got {}", tf.describe());
      ParamSet& set = scene.techniqueParams[technique];
      for (const auto& [param, value] : params.items()) {
        const Field pf = tf.child(param);
        set.set(param, readParamValue(pf), fmt::format("{}: {}", source, pf.path()));
      }
    }
  }
  return scene;
}

std::string sceneToJson(const Scene& scene) {
  json camera = {{"position", vec3Json(scene.camera.position)},
                 {"look_at", vec3Json(scene.camera.lookAt)},
                 {"up", vec3Json(scene.camera.up)},
                 {"fov_y", floatJson(scene.camera.fovYDegrees)}};
  // One line per top-level field, per light and per object: readable, and compact for big meshes.
  std::string out = "{\n";
  out += "  \"name\": " + json(scene.name).dump() + ",\n";
  out += "  \"image\": " + json({{"width", scene.image.width}, {"height", scene.image.height}}).dump() + ",\n";
  out += "  \"camera\": " + camera.dump() + ",\n";
  out += "  \"ambient\": " + floatJson(scene.ambient).dump() + ",\n";
  out += "  \"lights\": [";
  for (size_t i = 0; i < scene.lights.size(); ++i)
    out += (i ? ",\n    " : "\n    ") + lightJson(scene.lights[i]).dump();
  out += scene.lights.empty() ? "],\n" : "\n  ],\n";
  out += "  \"objects\": [";
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& object = scene.objects[i];
    json mesh;
    mesh["positions"] = json::array();
    for (const Vec3& p : object.mesh.positions) mesh["positions"].push_back(vec3Json(p));
    mesh["triangles"] = json::array();
    for (const glm::uvec3& t : object.mesh.triangles) mesh["triangles"].push_back({t.x, t.y, t.z});
    if (!object.mesh.normals.empty()) {
      mesh["normals"] = json::array();
      for (const Vec3& n : object.mesh.normals) mesh["normals"].push_back(vec3Json(n));
    }
    json o = {
        {"name", object.name}, {"id", object.id}, {"albedo", vec3Json(object.albedo)}, {"inline", std::move(mesh)}};
    if (object.sphere)
      o["analytic_sphere"] = {{"center", vec3Json(object.sphere->center)},
                              {"radius", floatJson(object.sphere->radius)}};
    out += (i ? ",\n    " : "\n    ") + o.dump();
  }
  out += scene.objects.empty() ? "]" : "\n  ]";
  if (!scene.techniqueParams.empty()) {
    json t = json::object();
    for (const auto& [technique, set] : scene.techniqueParams) {
      json params = json::object();
      for (const auto& [name, entry] : set.entries()) params[name] = paramJson(entry.value);
      t[technique] = std::move(params);
    }
    out += ",\n  \"techniques\": " + t.dump();
  }
  if (scene.motion) {
    const Motion& motion = *scene.motion;
    json m = {{"moves", motion.target == MotionTarget::Light ? "light" : "camera"}};
    if (motion.target == MotionTarget::Light) m["light"] = motion.lightIndex;
    m["path"] = json::array();
    for (const Vec3& p : motion.path) m["path"].push_back(vec3Json(p));
    m["frames"] = motion.frames;
    out += ",\n  \"motion\": " + m.dump();
  }
  out += "\n}\n";
  return out;
}

std::vector<BuiltinScene> builtinScenes() {
  std::vector<BuiltinScene> scenes;
  for (const auto& [stem, text] : detail::embeddedScenes()) {
    const json j = parseJson(std::string(text), fmt::format("built-in:{}", stem));
    std::string description;
    if (j.is_object() && j.contains("description") && j["description"].is_string())
      description = j["description"].get<std::string>();
    // The first sentence (a period, a space and a capital: "Fig. 7" does not end it), so the
    // list shows one line per scene.
    for (size_t end = description.find(". "); end != std::string::npos; end = description.find(". ", end + 1))
      if (end + 2 < description.size() && std::isupper(static_cast<unsigned char>(description[end + 2]))) {
        description.resize(end + 1);
        break;
      }
    scenes.push_back({std::string(stem), description});
  }
  return scenes;
}

Scene loadScene(const std::string& nameOrPath, const SceneLoadOptions& options) {
  for (const auto& [stem, text] : detail::embeddedScenes()) {
    if (stem != nameOrPath) continue;
    Scene scene = parseScene(std::string(text), fmt::format("built-in:{}", stem), ".", options);
    return scene;
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(nameOrPath, ec)) {
    std::vector<std::string> names;
    for (const auto& entry : detail::embeddedScenes()) names.emplace_back(entry.first);
    fail("{}: neither a built-in scene ({}) nor a readable scene file", nameOrPath, fmt::join(names, ", "));
  }
  const std::string text = readFileText(nameOrPath);
  const std::filesystem::path parent = std::filesystem::path(nameOrPath).parent_path();
  Scene scene = parseScene(text, nameOrPath, parent.empty() ? "." : parent.string(), options);
  scene.inputFiles.insert(scene.inputFiles.begin(), nameOrPath);
  return scene;
}

}  // namespace penumbra
