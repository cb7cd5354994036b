// Tests of the JSON scene format (src/io/scene_file.cpp): the built-in scenes load and are sane, a
// scene written by sceneToJson reads back equal, the documented example parses, and every error
// path names the file, the field path and what was expected.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

using json = nlohmann::json;

// A minimal valid scene; tests edit one field of it at a time.
json baseScene() {
  return json::parse(R"({
    "name": "base",
    "camera": {"position": [0, 2, 5], "look_at": [0, 0, 0]},
    "lights": [{"type": "sphere", "center": [0, 4, 0], "radius": 0.5}],
    "objects": [
      {"name": "ground", "primitive": {"type": "plane", "size": [4, 4]}},
      {"name": "ball", "albedo": 0.5, "primitive": {"type": "sphere", "radius": 0.5, "segments": 8, "rings": 4},
       "transform": {"translate": [0, 1, 0]}}
    ]
  })");
}

// Parses `j` and returns the error message; fails the test when it parses.
std::string errorOf(const std::string& text, const std::string& source = "scenes/x.json") {
  try {
    parseScene(text, source);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an error for: " << text.substr(0, 300);
  return "";
}
std::string errorOfJson(const json& j) { return errorOf(j.dump()); }

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE((haystack).find(needle), std::string::npos) << "message: " << (haystack)

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A folder of its own under the system temp dir, removed at the end.
class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("penumbra_scene_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name, const std::string& text) const {
    const std::string p = (path_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// ---------------------------------------------------------------------------------------------
// Equality of scenes, field by field (exact: the writer keeps full float precision).

void expectSameMesh(const Mesh& a, const Mesh& b, const std::string& what) {
  EXPECT_EQ(a.positions, b.positions) << what;
  EXPECT_EQ(a.normals, b.normals) << what;
  EXPECT_EQ(a.triangles, b.triangles) << what;
}

void expectSameLight(const Light& a, const Light& b) {
  EXPECT_EQ(a.shape(), b.shape());
  EXPECT_EQ(a.profile(), b.profile());
  EXPECT_EQ(a.intensity(), b.intensity());
  EXPECT_EQ(a.center(), b.center());
  EXPECT_EQ(a.radius(), b.radius());
  EXPECT_EQ(a.normal(), b.normal());
  EXPECT_EQ(a.u(), b.u());
  EXPECT_EQ(a.v(), b.v());
  EXPECT_EQ(a.a(), b.a());
  EXPECT_EQ(a.b(), b.b());
  EXPECT_EQ(a.direction(), b.direction());
  EXPECT_EQ(a.angularDiameter(), b.angularDiameter());
  EXPECT_EQ(a.vertices(), b.vertices());
}

void expectSameScene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.image.width, b.image.width);
  EXPECT_EQ(a.image.height, b.image.height);
  EXPECT_EQ(a.ambient, b.ambient);
  EXPECT_EQ(a.camera.position, b.camera.position);
  EXPECT_EQ(a.camera.lookAt, b.camera.lookAt);
  EXPECT_EQ(a.camera.up, b.camera.up);
  EXPECT_EQ(a.camera.fovYDegrees, b.camera.fovYDegrees);
  ASSERT_EQ(a.lights.size(), b.lights.size());
  for (size_t i = 0; i < a.lights.size(); ++i) expectSameLight(a.lights[i], b.lights[i]);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    EXPECT_EQ(a.objects[i].name, b.objects[i].name);
    EXPECT_EQ(a.objects[i].id, b.objects[i].id);
    EXPECT_EQ(a.objects[i].albedo, b.objects[i].albedo);
    expectSameMesh(a.objects[i].mesh, b.objects[i].mesh, a.objects[i].name);
  }
  ASSERT_EQ(a.techniqueParams.size(), b.techniqueParams.size());
  for (const auto& [technique, set] : a.techniqueParams) {
    ASSERT_EQ(b.techniqueParams.count(technique), 1u) << technique;
    const auto& ea = set.entries();
    const auto& eb = b.techniqueParams.at(technique).entries();
    ASSERT_EQ(ea.size(), eb.size());
    for (const auto& [name, entry] : ea) {
      ASSERT_EQ(eb.count(name), 1u) << name;
      EXPECT_EQ(entry.value, eb.at(name).value) << name;
      EXPECT_EQ(entry.source, eb.at(name).source) << name;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Built-in scenes.

TEST(BuiltinScenes, ListsThePapersSetups) {
  std::vector<std::string> names;
  for (const BuiltinScene& s : builtinScenes()) {
    names.push_back(s.name);
    // One line: the first sentence of the scene's description.
    EXPECT_GT(s.description.size(), 20u) << s.name;
    EXPECT_EQ(s.description.back(), '.') << s.name;
    EXPECT_EQ(s.description.find('\n'), std::string::npos) << s.name;
  }
  for (const char* expected : {"torus", "crowded", "triangle", "spheres", "linear", "slit", "concave"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
}

TEST(BuiltinScenes, EveryOneLoadsAndIsSane) {
  for (const BuiltinScene& info : builtinScenes()) {
    SCOPED_TRACE(info.name);
    const Scene s = loadScene(info.name);
    EXPECT_EQ(s.name, info.name);
    EXPECT_EQ(s.source, "built-in:" + info.name);
    EXPECT_GE(s.lights.size(), 1u);
    EXPECT_GE(s.objects.size(), 2u);
    EXPECT_EQ(s.image.width, 512);
    EXPECT_EQ(s.image.height, 512);
    EXPECT_LE(s.triangleCount(), s.name == "engine" ? 130000u : 40000u);  // engine: a real CAD assembly
    std::set<int32_t> ids;
    for (const Object& o : s.objects) {
      EXPECT_TRUE(ids.insert(o.id).second) << o.name;
      EXPECT_GT(o.mesh.triangleCount(), 0u) << o.name;
    }
    // A ground plane at y = 0 under everything, and every light above every object.
    const Bounds3 b = s.bounds();
    EXPECT_EQ(b.lower.y, 0.0f);
    for (const Light& l : s.lights)
      if (!l.isDirectional()) {
        EXPECT_GT(l.center().y - l.extent(), b.upper.y);
      }
    // The camera sees the scene's centre.
    const Vec3 toCentre = glm::normalize(b.center() - s.camera.position);
    EXPECT_GT(glm::dot(toCentre, glm::normalize(s.camera.lookAt - s.camera.position)),
              std::cos(radians(s.camera.fovYDegrees / 2)));
  }
}

TEST(BuiltinScenes, ConcaveHasFourConvexLightsAndAnL) {
  const Scene s = loadScene("concave");
  ASSERT_EQ(s.lights.size(), 5u);
  for (size_t i = 0; i < 4; ++i) EXPECT_TRUE(s.lights[i].convex()) << "light " << i;
  // Light 4: the 1.2 square of light 0 without its +x +z quarter, at the same height.
  const Light& l = s.lights[4];
  EXPECT_EQ(l.shape(), LightShape::Polygon);
  EXPECT_FALSE(l.convex());
  EXPECT_NEAR(l.area(), 0.75f * s.lights[0].area(), 1e-6f);
  EXPECT_NEAR(l.center().y, 4.0f, 1e-6f);
  EXPECT_NEAR(l.center().x, -0.1f, 1e-6f);  // the three quarters' centres (+-0.3) averaged
  EXPECT_NEAR(l.center().z, -0.1f, 1e-6f);
  EXPECT_EQ(l.convexParts().size(), 2u);
}

TEST(BuiltinScenes, ConcaveOccluderIsClosedAndOutward) {
  const Scene s = loadScene("concave");
  const Object* slab = s.findObject(1);
  ASSERT_NE(slab, nullptr);
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  double volume = 0.0;
  for (const glm::uvec3& t : slab->mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
    volume += glm::dot(DVec3(slab->mesh.positions[t.x]),
                       glm::cross(DVec3(slab->mesh.positions[t.y]), DVec3(slab->mesh.positions[t.z]))) /
              6.0;
  }
  for (const auto& [e, n] : edges) {
    EXPECT_EQ(n, 1);
    EXPECT_EQ(edges.count({e.second, e.first}), 1u);
  }
  EXPECT_NEAR(volume, (2.0 * 2.0 - 0.8 * 1.4) * 0.3, 1e-5);  // the U's area times its thickness
}

TEST(BuiltinScenes, TriangleSceneMatchesLawlorsSetup) {
  const Scene s = loadScene("triangle");
  ASSERT_EQ(s.lights.size(), 1u);
  EXPECT_TRUE(s.lights[0].isDirectional());
  EXPECT_EQ(s.lights[0].direction(), Vec3(0, 1, 0));
  const Object* tri = s.findObject(1);
  ASSERT_NE(tri, nullptr);
  ASSERT_EQ(tri->mesh.positions.size(), 3u);
  std::vector<float> heights;
  for (const Vec3& p : tri->mesh.positions) heights.push_back(p.y);
  std::sort(heights.begin(), heights.end());
  EXPECT_EQ(heights[0], 0.0f);               // touches the ground
  EXPECT_GT(heights[1], 0.0f);               // slightly raised
  EXPECT_GT(heights[2], 5.0f * heights[1]);  // far off the ground
}

TEST(LoadScene, UnknownNameListsTheBuiltins) {
  try {
    loadScene("no-such-scene");
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_CONTAINS(m, "no-such-scene");
    EXPECT_CONTAINS(m, "torus");
    EXPECT_CONTAINS(m, "crowded");
  }
}

TEST(LoadScene, ReadsAFileAndResolvesMeshesRelativeToIt) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() + "/meshes");
  dir.file("meshes/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n");
  json j = baseScene();
  j.erase("name");
  j["objects"][1].erase("primitive");
  j["objects"][1]["mesh"] = "meshes/tri.obj";
  const std::string path = dir.file("my_scene.json", j.dump());
  const Scene s = loadScene(path);
  EXPECT_EQ(s.name, "my_scene");  // the file stem when the file has no name
  EXPECT_EQ(s.source, path);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[1].mesh.triangleCount(), 1u);
  // Translated by the object's transform.
  EXPECT_EQ(s.objects[1].mesh.bounds().lower, Vec3(0, 1, -1));
}

// ---------------------------------------------------------------------------------------------
// Reading: defaults, transforms, all light types, techniques.

TEST(ParseScene, DefaultsAndIds) {
  const Scene s = parseScene(baseScene().dump(), "base.json");
  EXPECT_EQ(s.name, "base");
  EXPECT_EQ(s.image.width, 512);
  EXPECT_EQ(s.image.height, 512);
  EXPECT_EQ(s.camera.up, Vec3(0, 1, 0));
  EXPECT_EQ(s.camera.fovYDegrees, 45.0f);
  EXPECT_EQ(s.ambient, 0.05f);
  EXPECT_EQ(s.objects[0].id, 0);
  EXPECT_EQ(s.objects[1].id, 1);
  EXPECT_EQ(s.objects[0].albedo, Vec3(0.8f));
  EXPECT_EQ(s.objects[1].albedo, Vec3(0.5f));
  EXPECT_EQ(s.lights[0].intensity(), 1.0f);
}

TEST(ParseScene, EmptyLightsAndObjectsParse) {
  json j = baseScene();
  j["lights"] = json::array();
  j["objects"] = json::array();
  const Scene s = parseScene(j.dump(), "empty.json");
  EXPECT_TRUE(s.lights.empty());
  EXPECT_TRUE(s.objects.empty());
}

TEST(ParseScene, TransformScalesThenRotatesXYZThenTranslates) {
  json j = baseScene();
  j["objects"] = json::array(
      {json::parse(R"({"name": "t", "primitive": {"type": "triangle", "vertices": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]},
      "transform": {"scale": [2, 3, 4], "rotate": [90, 90, 0], "translate": [10, 20, 30]}})")});
  const Scene s = parseScene(j.dump(), "t.json");
  const auto& p = s.objects[0].mesh.positions;
  // x axis: scaled to 2x, Rx leaves it, Ry(90) takes +x to -z: (0, 0, -2).
  // y axis: 3y, Rx(90) takes +y to +z, Ry(90) takes +z to +x: (3, 0, 0).
  // z axis: 4z, Rx(90) takes +z to -y, Ry leaves it: (0, -4, 0).
  const Vec3 t(10, 20, 30);
  EXPECT_NEAR(glm::distance(p[0], t + Vec3(0, 0, -2)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::distance(p[1], t + Vec3(3, 0, 0)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::distance(p[2], t + Vec3(0, -4, 0)), 0.0f, 1e-5f);
}

TEST(ParseScene, FitScalesUniformlyAndSetsTheBottomCentreOnBase) {
  json j = baseScene();
  // A 2 x 4 x 1 box rotated 90 degrees about z (so 4 wide, 2 tall, 1 deep), then fitted to size 8 on (1, 2, 3).
  j["objects"] = json::array({json::parse(R"({"name": "b", "primitive": {"type": "box", "size": [2, 4, 1]},
      "transform": {"rotate": [0, 0, 90], "translate": [100, -50, 7]}, "fit": {"size": 8, "base": [1, 2, 3]}})")});
  const Scene s = parseScene(j.dump(), "f.json");
  const Bounds3 b = s.objects[0].mesh.bounds();
  // The largest side (4, along x after the rotation) becomes 8: a scale of 2 in every direction.
  EXPECT_NEAR(b.lower.x, 1.0f - 4.0f, 1e-4f);
  EXPECT_NEAR(b.upper.x, 1.0f + 4.0f, 1e-4f);
  EXPECT_NEAR(b.lower.y, 2.0f, 1e-4f);
  EXPECT_NEAR(b.upper.y, 2.0f + 4.0f, 1e-4f);
  EXPECT_NEAR(b.lower.z, 3.0f - 1.0f, 1e-4f);
  EXPECT_NEAR(b.upper.z, 3.0f + 1.0f, 1e-4f);
  // base defaults to the origin; a sphere stays a true sphere (uniform scale).
  j["objects"] =
      json::array({json::parse(R"({"name": "s", "primitive": {"type": "sphere", "radius": 3}, "fit": {"size": 1}})")});
  const Scene t = parseScene(j.dump(), "f.json");
  ASSERT_TRUE(t.objects[0].sphere.has_value());
  EXPECT_NEAR(t.objects[0].sphere->radius, 0.5f, 1e-5f);
  EXPECT_NEAR(glm::distance(t.objects[0].sphere->center, Vec3(0.0f, 0.5f, 0.0f)), 0.0f, 1e-5f);
}

TEST(ParseScene, MatrixIsRowMajorAffine) {
  json j = baseScene();
  j["objects"][1].erase("transform");
  j["objects"][1]["matrix"] = json::parse("[[1, 0, 0, 5], [0, 1, 0, 6], [0, 0, 1, 7], [0, 0, 0, 1]]");
  const Scene s = parseScene(j.dump(), "m.json");
  const Vec3 c = s.objects[1].mesh.bounds().center();
  EXPECT_NEAR(glm::distance(c, Vec3(5, 6, 7)), 0.0f, 1e-5f);
}

TEST(ParseScene, EveryLightType) {
  json j = baseScene();
  j["lights"] = json::parse(R"([
    {"type": "sphere", "center": [0, 4, 0], "radius": 0.5, "intensity": 2},
    {"type": "disk", "center": [0, 4, 0], "normal": [0, -2, 0], "radius": 0.3},
    {"type": "rect", "center": [0, 4, 0], "u": [0.5, 0, 0], "v": [0, 0, 0.25]},
    {"type": "segment", "a": [-1, 4, 0], "b": [1, 4, 0]},
    {"type": "polygon", "vertices": [[0, 4, 0], [1, 4, 0], [0, 4, 1]]},
    {"type": "directional", "direction": [0, 1, 0], "angular_diameter": 0.53, "profile": "limb-darkened"},
    {"type": "polygon", "vertices": [[0, 4, 0], [2, 4, 0], [2, 4, 1], [1, 4, 1], [1, 4, 2], [0, 4, 2]]}
  ])");
  const Scene s = parseScene(j.dump(), "lights.json");
  ASSERT_EQ(s.lights.size(), 7u);
  EXPECT_EQ(s.lights[0].shape(), LightShape::Sphere);
  EXPECT_EQ(s.lights[0].intensity(), 2.0f);
  EXPECT_EQ(s.lights[1].shape(), LightShape::Disk);
  EXPECT_EQ(s.lights[1].normal(), Vec3(0, -1, 0));
  EXPECT_EQ(s.lights[2].shape(), LightShape::Rect);
  EXPECT_EQ(s.lights[3].shape(), LightShape::Segment);
  EXPECT_EQ(s.lights[4].shape(), LightShape::Polygon);
  EXPECT_EQ(s.lights[5].shape(), LightShape::Directional);
  EXPECT_EQ(s.lights[5].profile(), LightProfile::LimbDarkened);
  EXPECT_NEAR(s.lights[5].angularDiameter(), 0.53 * M_PI / 180.0, 1e-7);
  // A concave (L-shaped) polygon is a light like any other, its vertices kept as given.
  EXPECT_EQ(s.lights[6].shape(), LightShape::Polygon);
  EXPECT_FALSE(s.lights[6].convex());
  EXPECT_EQ(s.lights[6].vertices().size(), 6u);
  EXPECT_EQ(s.lights[6].vertices()[3], Vec3(1, 4, 1));
  EXPECT_NEAR(s.lights[6].area(), 3.0f, 1e-6f);
}

TEST(ParseScene, TechniqueParametersKeepTypeAndSource) {
  json j = baseScene();
  j["techniques"] = json::parse(R"({"pcss": {"kernel": 5, "scale": 0.5, "soft": true, "mode": "auto"}})");
  const Scene s = parseScene(j.dump(), "scenes/x.json");
  ASSERT_EQ(s.techniqueParams.count("pcss"), 1u);
  const auto& e = s.techniqueParams.at("pcss").entries();
  EXPECT_EQ(e.at("kernel").value, ParamValue(int64_t{5}));
  EXPECT_EQ(e.at("scale").value, ParamValue(0.5));
  EXPECT_EQ(e.at("soft").value, ParamValue(true));
  EXPECT_EQ(e.at("mode").value, ParamValue(std::string("auto")));
  EXPECT_EQ(e.at("kernel").source, "scenes/x.json: techniques.pcss.kernel");
}

// ---------------------------------------------------------------------------------------------
// Round trip.

TEST(SceneToJson, RoundTripIsExact) {
  json j = baseScene();
  j["image"] = {{"width", 320}, {"height", 200}};
  j["ambient"] = 0.1;
  j["camera"]["fov_y"] = 33.3;
  j["lights"] = json::parse(R"([
    {"type": "sphere", "center": [0.1, 4.3, 0.7], "radius": 0.3333},
    {"type": "disk", "center": [0, 4, 0], "normal": [0.3, -1, 0.2], "radius": 0.3},
    {"type": "rect", "center": [0, 4, 0], "u": [0.5, 0, 0], "v": [0, 0, 0.25], "intensity": 3.7},
    {"type": "segment", "a": [-1, 4, 0], "b": [1, 4.5, 0]},
    {"type": "polygon", "vertices": [[0, 4, 0], [1, 4, 0], [1.2, 4, 0.9], [0, 4, 1]]},
    {"type": "directional", "direction": [0.2, 1, 0.1], "angular_diameter": 0.53, "profile": "limb-darkened"},
    {"type": "polygon", "vertices": [[0.1, 4, 0], [2, 4, 0], [2, 4, 1.3], [1, 4, 1.3], [1, 4, 2], [0.1, 4, 2]]}
  ])");
  j["objects"].push_back(json::parse(R"({"name": "torus", "id": 17, "albedo": [0.1, 0.2, 0.3],
      "primitive": {"type": "torus", "major_radius": 1, "minor_radius": 0.3, "major_segments": 12, "minor_segments": 6},
      "transform": {"rotate": [13, 27, 41], "scale": [1, 2, 0.7], "translate": [0.1, 0.2, 0.3]}})"));
  j["techniques"] = json::parse(R"({"pcss": {"kernel": 5, "scale": 0.1}, "brabec": {"jitter": false, "mode": "x"}})");
  const Scene original = parseScene(j.dump(), "scenes/x.json");
  const std::string written = sceneToJson(original);
  const Scene back = parseScene(written, "scenes/x.json");
  expectSameScene(original, back);
  // And once more: writing is deterministic.
  EXPECT_TRUE(sceneToJson(back) == written);
}

TEST(SceneToJson, DerivedUnitVectorsAndAnglesRoundTrip) {
  // Lights keep normalized vectors and radians; the writer must find file values that read back to
  // exactly those. Checked on many awkward directions and angles.
  uint32_t state = 12345u;
  const auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / 16777216.0f;
  };
  int failures = 0;
  for (int i = 0; i < 1000; ++i) {
    json j = baseScene();
    const Vec3 d(next() - 0.5f, next() + 0.1f, next() - 0.5f);
    j["lights"] = json::array(
        {{{"type", "disk"}, {"center", {0, 4, 0}}, {"normal", {d.x, -d.y, d.z}}, {"radius", 0.3}},
         {{"type", "directional"}, {"direction", {d.x, d.y, d.z}}, {"angular_diameter", 0.1 + 20.0 * next()}}});
    const Scene original = parseScene(j.dump(), "x.json");
    const Scene back = parseScene(sceneToJson(original), "x.json");
    failures += back.lights[0].normal() != original.lights[0].normal();
    failures += back.lights[1].direction() != original.lights[1].direction();
    failures += back.lights[1].angularDiameter() != original.lights[1].angularDiameter();
  }
  EXPECT_EQ(failures, 0);
}

TEST(SceneToJson, BuiltinScenesRoundTrip) {
  for (const BuiltinScene& info : builtinScenes()) {
    SCOPED_TRACE(info.name);
    const Scene s = loadScene(info.name);
    expectSameScene(s, parseScene(sceneToJson(s), s.source));
  }
}

// ---------------------------------------------------------------------------------------------
// The documented example (docs/scene-format.md) parses as it stands.

TEST(SceneFormatDoc, CompleteExampleParses) {
  const std::string doc = readText(std::string(PENUMBRA_SOURCE_DIR) + "/docs/scene-format.md");
  ASSERT_FALSE(doc.empty());
  const std::string startTag = "<!-- complete-example -->\n```json\n";
  const size_t start = doc.find(startTag);
  ASSERT_NE(start, std::string::npos) << "the doc must hold its complete example after " << startTag;
  const size_t end = doc.find("```", start + startTag.size());
  ASSERT_NE(end, std::string::npos);
  const std::string example = doc.substr(start + startTag.size(), end - start - startTag.size());
  // The example uses a mesh file; give it one next to the scene.
  TempDir dir;
  std::filesystem::create_directories(dir.path() + "/meshes");
  dir.file("meshes/rock.obj", "v -0.5 0 0\nv 0.5 0 0\nv 0 0 -1\nv 0 1 -0.3\nf 1 2 4\nf 2 3 4\nf 3 1 4\nf 1 3 2\n");
  const Scene s = parseScene(example, "example.json", dir.path());
  EXPECT_EQ(s.name, "example");
  EXPECT_GE(s.lights.size(), 1u);
  EXPECT_GE(s.objects.size(), 3u);
  EXPECT_FALSE(s.techniqueParams.empty());
  // Its technique parameters are real ones: the registry accepts them.
  for (const auto& [technique, given] : s.techniqueParams)
    EXPECT_NO_THROW(resolveParams(technique, findTechnique(technique).params, given)) << technique;
}

// ---------------------------------------------------------------------------------------------
// Errors: each names the file and the field path, and what was expected.

struct ErrorCase {
  std::string what;
  std::function<void(json&)> edit;
  std::vector<std::string> expected;  // substrings of the message
};

TEST(SceneErrors, EachNamesFileFieldAndExpectation) {
  const std::vector<ErrorCase> cases = {
      {"unknown top-level key",
       [](json& j) { j["lihgts"] = json::array(); },
       {"scenes/x.json", "unknown key 'lihgts'", "did you mean 'lights'"}},
      {"unknown object key",
       [](json& j) { j["objects"][1]["colour"] = 1; },
       {"scenes/x.json: objects[1]: unknown key 'colour'"}},
      {"missing camera", [](json& j) { j.erase("camera"); }, {"scenes/x.json", "missing required key 'camera'"}},
      {"a model of assimp-testmodels that is not there",
       [](json& j) {
         j["objects"][1].erase("primitive");
         j["objects"][1]["mesh"] = std::string(kAssimpTestModels) + "OBJ/no_such_model.obj";
       },
       {"scenes/x.json: objects[1].mesh: /usr/share/assimp/models/OBJ/no_such_model.obj: mesh file not found",
        "Debian's assimp-testmodels package"}},
      {"a light beyond the ray tracer's reach",
       [](json& j) {
         j["lights"][0]["center"] = {0, 3e38, 0};
       },
       {"scenes/x.json: lights[0]: expected world coordinates within +-1e+18", "the light reaches 3e+38"}},
      {"an object scaled beyond the ray tracer's reach",
       [](json& j) { j["objects"][1]["transform"]["scale"] = 3e38; },
       {"scenes/x.json: objects[1].transform: transform is singular or overflows (determinant inf)"}},
      {"an object translated beyond the ray tracer's reach",
       [](json& j) {
         j["objects"][1]["transform"]["translate"] = {0, 2e18, 0};
       },
       {"scenes/x.json: objects[1]: expected world coordinates within +-1e+18",
        "the object (after its transform) reaches"}},
      {"fit without size",
       [](json& j) { j["objects"][1]["fit"] = json::object(); },
       {"scenes/x.json: objects[1].fit: missing required key 'size'"}},
      {"fit to a zero size",
       [](json& j) {
         j["objects"][1]["fit"] = {{"size", 0}};
       },
       {"scenes/x.json: objects[1].fit.size: expected a number > 0"}},
      {"missing lights", [](json& j) { j.erase("lights"); }, {"missing required key 'lights'"}},
      {"missing object name",
       [](json& j) { j["objects"][0].erase("name"); },
       {"objects[0]: missing required key 'name'"}},
      {"rotate of 2 numbers",
       [](json& j) {
         j["objects"][1]["transform"]["rotate"] = {1, 2};
       },
       {"scenes/x.json: objects[1].transform.rotate: expected an array of 3 numbers"}},
      {"string where a number goes",
       [](json& j) { j["objects"][1]["primitive"]["radius"] = "big"; },
       {"objects[1].primitive.radius: expected a number, got a string"}},
      {"negative radius",
       [](json& j) { j["objects"][1]["primitive"]["radius"] = -1; },
       {"objects[1].primitive.radius: expected a number > 0"}},
      {"float where an integer goes",
       [](json& j) { j["objects"][1]["primitive"]["segments"] = 8.5; },
       {"objects[1].primitive.segments: expected an integer"}},
      {"too few segments",
       [](json& j) { j["objects"][1]["primitive"]["segments"] = 2; },
       {"objects[1].primitive.segments: expected an integer in [3,"}},
      {"number out of float range",
       [](json& j) { j["camera"]["position"][0] = 1e300; },
       {"camera.position[0]: expected a finite number"}},
      {"unknown primitive",
       [](json& j) { j["objects"][1]["primitive"]["type"] = "cone"; },
       {"objects[1].primitive.type: unknown primitive type \"cone\"", "plane, box, sphere"}},
      {"two geometries",
       [](json& j) { j["objects"][1]["mesh"] = "a.obj"; },
       {"objects[1]: expected exactly one of 'primitive', 'mesh' or 'inline'"}},
      {"no geometry", [](json& j) { j["objects"][1].erase("primitive"); }, {"objects[1]: expected exactly one of"}},
      {"transform and matrix",
       [](json& j) { j["objects"][1]["matrix"] = json::parse("[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]"); },
       {"objects[1]: expected at most one of 'transform' and 'matrix'"}},
      {"projective matrix",
       [](json& j) {
         j["objects"][1].erase("transform");
         j["objects"][1]["matrix"] = json::parse("[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]]");
       },
       {"objects[1].matrix[3]: expected [0, 0, 0, 1]"}},
      {"zero scale",
       [](json& j) { j["objects"][1]["transform"]["scale"] = 0; },
       {"objects[1].transform.scale: expected non-zero"}},
      {"duplicate explicit ids",
       [](json& j) {
         j["objects"][0]["id"] = 3;
         j["objects"][1]["id"] = 3;
       },
       {"objects[1]: duplicate object id 3", "objects[0]"}},
      {"explicit id equal to another's index",
       [](json& j) { j["objects"][0]["id"] = 1; },
       {"objects[1]: duplicate object id 1"}},
      {"negative id", [](json& j) { j["objects"][0]["id"] = -1; }, {"objects[0].id: expected an integer in [0,"}},
      {"albedo above 1",
       [](json& j) {
         j["objects"][0]["albedo"] = {0.5, 1.5, 0.5};
       },
       {"objects[0].albedo: expected reflectances in [0, 1]"}},
      {"albedo as a string",
       [](json& j) { j["objects"][0]["albedo"] = "red"; },
       {"objects[0].albedo: expected a number or an array of 3 numbers"}},
      {"unknown light type",
       [](json& j) { j["lights"][0]["type"] = "spot"; },
       {"lights[0].type: unknown light type \"spot\""}},
      {"light without type", [](json& j) { j["lights"][0].erase("type"); }, {"lights[0]: missing required key 'type'"}},
      {"zero light radius", [](json& j) { j["lights"][0]["radius"] = 0; }, {"lights[0].radius: expected a number > 0"}},
      {"key of another light type",
       [](json& j) {
         j["lights"][0]["normal"] = {0, 1, 0};
       },
       {"lights[0]: unknown key 'normal'"}},
      {"degenerate disk normal",
       [](json& j) {
         j["lights"][0] = json::parse(R"({"type": "disk", "center": [0, 4, 0], "normal": [0, 0, 0], "radius": 1})");
       },
       {"scenes/x.json: lights[0].normal: disk normal must be a non-zero vector"}},
      {"self-intersecting polygon light",
       [](json& j) {
         j["lights"][0] =
             json::parse(R"({"type": "polygon", "vertices": [[0,4,0],[2,4,0],[2,4,1],[1,4,1],[1,4,-1],[0,4,2]]})");
       },
       {"scenes/x.json: lights[0].vertices: polygon edges 0 and 3 cross; expected a simple polygon"}},
      {"bow-tie polygon light",
       [](json& j) {
         j["lights"][0] = json::parse(R"({"type": "polygon", "vertices": [[0,4,0],[1,4,0],[0,4,1],[1,4,1]]})");
       },
       {"scenes/x.json: lights[0].vertices: polygon edges 1 and 3 cross; expected a simple polygon"}},
      {"polygon light with a repeated vertex",
       [](json& j) {
         j["lights"][0] =
             json::parse(R"({"type": "polygon", "vertices": [[0,4,0],[2,4,0],[1,4,1],[2,4,2],[1,4,1],[0,4,2]]})");
       },
       {"scenes/x.json: lights[0].vertices: polygon vertices 2 and 4 coincide; expected distinct vertices"}},
      {"non-planar polygon light",
       [](json& j) {
         j["lights"][0] =
             json::parse(R"({"type": "polygon", "vertices": [[0,4,0],[2,4,0],[2,4,1],[1,5,1],[1,4,2],[0,4,2]]})");
       },
       {"scenes/x.json: lights[0].vertices: polygon is not planar", "expected all vertices in one plane"}},
      {"zero-area polygon light",
       [](json& j) { j["lights"][0] = json::parse(R"({"type": "polygon", "vertices": [[0,4,0],[1,4,0],[3,4,0]]})"); },
       {"scenes/x.json: lights[0].vertices: polygon has zero area"}},
      {"rect with parallel edges",
       [](json& j) {
         j["lights"][0] = json::parse(R"({"type": "rect", "center": [0,4,0], "u": [1,0,0], "v": [1,0,0.1]})");
       },
       {"scenes/x.json: lights[0]: rect half-edges u and v must be perpendicular"}},
      {"directional angle out of range",
       [](json& j) {
         j["lights"][0] = json::parse(R"({"type": "directional", "direction": [0,1,0], "angular_diameter": 180})");
       },
       {"lights[0].angular_diameter: expected an angle in (0, 180) degrees"}},
      {"unknown profile",
       [](json& j) {
         j["lights"][0] = json::parse(
             R"({"type": "directional", "direction": [0,1,0], "angular_diameter": 1, "profile": "gaussian"})");
       },
       {"lights[0].profile: expected \"uniform\" or \"limb-darkened\""}},
      {"negative intensity",
       [](json& j) { j["lights"][0]["intensity"] = -2; },
       {"lights[0].intensity: expected a number >= 0"}},
      {"camera looking at itself",
       [](json& j) { j["camera"]["look_at"] = j["camera"]["position"]; },
       {"scenes/x.json: camera: look_at must differ from position"}},
      {"camera fov", [](json& j) { j["camera"]["fov_y"] = 180; }, {"scenes/x.json: camera: fov_y must be in (0, 180)"}},
      {"image width zero",
       [](json& j) {
         j["image"] = {{"width", 0}, {"height", 10}};
       },
       {"image.width: expected an integer in [1, 16384]"}},
      {"technique param of wrong type",
       [](json& j) { j["techniques"] = json::parse(R"({"pcss": {"kernel": [1, 2]}})"); },
       {"techniques.pcss.kernel: expected a number, a boolean or a string"}},
      {"technique not an object",
       [](json& j) { j["techniques"] = json::parse(R"({"pcss": 3})"); },
       {"techniques.pcss: expected an object"}},
      {"inline index out of range",
       [](json& j) {
         j["objects"][1] = json::parse(
             R"({"name": "m", "inline": {"positions": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0, 1, 3]]}})");
       },
       {"objects[1].inline.triangles[0][2]: expected an integer in [0, 2]"}},
      {"inline repeated index",
       [](json& j) {
         j["objects"][1] = json::parse(
             R"({"name": "m", "inline": {"positions": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0, 1, 1]]}})");
       },
       {"objects[1].inline.triangles[0]: expected 3 distinct vertex indices"}},
      {"inline normals count",
       [](json& j) {
         j["objects"][1] = json::parse(
             R"({"name": "m", "inline": {"positions": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0, 1, 2]], "normals": [[0,0,1]]}})");
       },
       {"objects[1].inline.normals: expected one normal per position (3), got 1"}},
      {"inline normal not unit",
       [](json& j) {
         j["objects"][1] = json::parse(
             R"({"name": "m", "inline": {"positions": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0, 1, 2]], "normals": [[0,0,1],[0,0,1],[0,0,2]]}})");
       },
       {"objects[1].inline.normals[2]: expected a unit vector"}},
      {"degenerate triangle primitive",
       [](json& j) {
         j["objects"][1]["primitive"] = json::parse(R"({"type": "triangle", "vertices": [[0,0,0],[1,1,1],[2,2,2]]})");
       },
       {"objects[1].primitive.vertices: triangle vertices must not be collinear"}},
      {"torus minor radius too large",
       [](json& j) {
         j["objects"][1]["primitive"] = json::parse(R"({"type": "torus", "major_radius": 1, "minor_radius": 1})");
       },
       {"objects[1].primitive.minor_radius: expected a number smaller than major_radius"}},
      {"missing mesh file",
       [](json& j) {
         j["objects"][1].erase("primitive");
         j["objects"][1]["mesh"] = "nowhere/missing.obj";
       },
       {"scenes/x.json: objects[1].mesh:", "nowhere/missing.obj", "not found"}},
      {"top level not an object",
       [](json& j) { j = json::array(); },
       {"scenes/x.json: expected a JSON object at the top level"}},
  };
  for (const ErrorCase& c : cases) {
    SCOPED_TRACE(c.what);
    json j = baseScene();
    c.edit(j);
    const std::string message = errorOfJson(j);
    EXPECT_EQ(message.rfind("scenes/x.json: ", 0), 0u) << "the message must start with the file: " << message;
    for (const std::string& e : c.expected) EXPECT_CONTAINS(message, e);
  }
}

TEST(SceneErrors, MalformedJsonGivesLineAndColumn) {
  const std::string message = errorOf("{\n  \"name\": \"x\",\n  \"camera\": {\"position\": [0, 1 2]}\n}");
  EXPECT_CONTAINS(message, "scenes/x.json: malformed JSON at line 3, column");
}

TEST(SceneErrors, DuplicateKeysAreRejected) {
  const std::string text =
      R"({"name": "x", "camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "fov_y": 30, "fov_y": 40},
                               "lights": [], "objects": []})";
  EXPECT_CONTAINS(errorOf(text), "scenes/x.json: camera.fov_y: duplicate key 'fov_y'");
  const std::string inArray = R"({"lights": [], "camera": {"position": [0, 2, 5], "look_at": [0, 0, 0]},
      "objects": [{"name": "a", "primitive": {"type": "box", "size": 1}}, {"name": "b", "name": "c", "primitive": {"type": "box", "size": 1}}]})";
  EXPECT_CONTAINS(errorOf(inArray), "scenes/x.json: objects[1].name: duplicate key 'name'");
}

TEST(SceneErrors, BadMeshFileIsNamed) {
  TempDir dir;
  dir.file("empty.obj", "");
  json j = baseScene();
  j["objects"][1].erase("primitive");
  j["objects"][1]["mesh"] = "empty.obj";
  try {
    parseScene(j.dump(), "scenes/x.json", dir.path());
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_CONTAINS(m, "scenes/x.json: objects[1].mesh:");
    EXPECT_CONTAINS(m, "empty.obj");
    EXPECT_CONTAINS(m, "empty");
  }
}

TEST(SceneFile, MotionIsReadCheckedAndWrittenBack) {
  json j = baseScene();
  j["motion"] = json::parse(R"({"moves": "light", "light": 0, "path": [[0, 4, 0], [0.2, 4, 0]], "frames": 6})");
  const Scene s = parseScene(j.dump(), "scenes/x.json");
  ASSERT_TRUE(s.motion.has_value());
  EXPECT_EQ(s.motion->target, MotionTarget::Light);
  EXPECT_EQ(s.motion->frames, 6);
  ASSERT_EQ(s.motion->path.size(), 2u);
  EXPECT_FLOAT_EQ(s.motion->path[1].x, 0.2f);
  // sceneToJson keeps it, so a report's scene.json reproduces the sequence.
  const Scene again = parseScene(sceneToJson(s), "again.json");
  ASSERT_TRUE(again.motion.has_value());
  EXPECT_EQ(again.motion->path, s.motion->path);
  EXPECT_EQ(again.motion->frames, 6);
  // Without a motion the scene's JSON has none (the reference cache's key of a still scene is unchanged).
  EXPECT_EQ(sceneToJson(parseScene(baseScene().dump(), "b.json")).find("motion"), std::string::npos);

  json camera = baseScene();
  camera["motion"] = json::parse(R"({"moves": "camera", "path": [[0, 2, 5], [1, 2, 5]]})");
  const Scene c = parseScene(camera.dump(), "scenes/x.json");
  EXPECT_EQ(c.motion->target, MotionTarget::Camera);
  EXPECT_EQ(c.motion->frames, 12);  // the default
}

TEST(SceneErrors, BadMotionIsNamed) {
  auto withMotion = [](const char* motion) {
    json j = baseScene();
    j["motion"] = json::parse(motion);
    return errorOfJson(j);
  };
  EXPECT_CONTAINS(withMotion(R"({"moves": "sun", "path": [[0, 4, 0], [1, 4, 0]]})"),
                  "scenes/x.json: motion.moves: expected \"light\" or \"camera\", got \"sun\"");
  EXPECT_CONTAINS(withMotion(R"({"moves": "light", "path": [[0, 4, 0]]})"),
                  "scenes/x.json: motion.path: expected an array of at least 2 key points");
  EXPECT_CONTAINS(withMotion(R"({"moves": "light", "light": 3, "path": [[0, 4, 0], [1, 4, 0]]})"),
                  "scenes/x.json: motion.light: expected an integer in [0, 0], got 3");
  EXPECT_CONTAINS(withMotion(R"({"moves": "light", "path": [[0, 4, 0], [1, 4, 0]], "frames": 1})"),
                  "scenes/x.json: motion.frames: expected an integer in [2, 1000]");
  EXPECT_CONTAINS(withMotion(R"({"moves": "light", "path": [[0, 4, 0], [0, 4, 0]]})"),
                  "scenes/x.json: motion: path has zero length");
  EXPECT_CONTAINS(withMotion(R"({"moves": "camera", "path": [[0, 2, 5], [0, 2, -5]], "frames": 3})"),
                  "scenes/x.json: motion: the camera at frame 1");
  EXPECT_CONTAINS(withMotion(R"({"moves": "light", "speed": 1, "path": [[0, 4, 0], [1, 4, 0]]})"),
                  "scenes/x.json: motion: unknown key 'speed'");
}

}  // namespace
}  // namespace penumbra
