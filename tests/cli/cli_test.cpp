// End-to-end tests of the `penumbra` binary (apps/penumbra): every kind of bad input ends in one
// line "penumbra: error: ..." naming what is wrong and exit code 1 (CLI11 usage errors: its own
// non-zero code); render and compare write their files; compare's table measures `none` against
// the reference. Tiny images (32 x 32, 4 spp) keep the whole file to a few seconds.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "penumbra/image_io.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string output;  // stdout and stderr together
};

// A small scene: a plane and a sphere under a sphere light.
const std::string kCamera = R"("camera": {"position": [0, 3, 5], "look_at": [0, 0, 0]})";
const std::string kLight = R"({"type": "sphere", "center": [0, 4, 0], "radius": 0.5})";
const std::string kObjects = R"([{"name": "ground", "primitive": {"type": "plane", "size": [4, 4]}},
  {"name": "ball", "id": 1, "primitive": {"type": "sphere", "radius": 0.5}, "transform": {"translate": [0, 1, 0]}}])";

std::string sceneJson(const std::string& lights, const std::string& objects, const std::string& extra = "") {
  return "{\"name\": \"tiny\", " + kCamera + ", \"lights\": [" + lights + "], \"objects\": " + objects + extra + "}";
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra_cli_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return name;
  }
  std::string read(const std::string& name) const {
    std::ifstream in(dir_ / name);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  bool exists(const std::string& name) const { return fs::exists(dir_ / name); }

  // Runs the binary in the test's directory.
  Result run(const std::string& args) const {
    const std::string command = "cd '" + dir_.string() + "' && '" PENUMBRA_CLI "' " + args + " 2>&1";
    Result r;
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return r;
    char buffer[4096];
    size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, n);
    const int status = pclose(pipe);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
  }

  // An error: exit code 1 and exactly one line "penumbra: error: ..." holding every piece of `expected`.
  void expectError(const std::string& args, const std::vector<std::string>& expected) const {
    const Result r = run(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.output;
    EXPECT_EQ(r.output.rfind("penumbra: error: ", 0), 0u) << args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << "\n" << r.output;
    for (const std::string& e : expected) EXPECT_NE(r.output.find(e), std::string::npos) << "missing '" << e << "' in: " << r.output;
  }

  fs::path dir_;
};

const std::string kTiny = "--width 32 --height 32 --spp 4 --out out";

TEST_F(CliTest, UnknownTechnique) {
  write("s.json", sceneJson(kLight, kObjects));
  expectError("render --scene s.json -t nope " + kTiny, {"unknown technique 'nope'", "reference", "raytraced-hard"});
  expectError("compare --scene s.json --techniques none,nope " + kTiny, {"unknown technique 'nope'"});
}

TEST_F(CliTest, UnknownParameter) {
  write("s.json", sceneJson(kLight, kObjects));
  expectError("render --scene s.json -t reference -p foo=1 " + kTiny, {"command line", "no parameter 'foo'", "spp"});
}

TEST_F(CliTest, OutOfRangeValue) {
  write("s.json", sceneJson(kLight, kObjects));
  expectError("render --scene s.json -t reference -p spp=0 " + kTiny, {"reference.spp = 0", "expected int"});
  expectError("render --scene s.json -t reference -p spp=abc " + kTiny, {"reference.spp = abc"});
}

TEST_F(CliTest, MalformedKeyValue) {
  write("s.json", sceneJson(kLight, kObjects));
  expectError("render --scene s.json -t reference -p spp " + kTiny, {"'spp'", "key=value"});
  expectError("compare --scene s.json --techniques none -p spp=2 " + kTiny, {"'spp=2'", "technique.key=value"});
}

TEST_F(CliTest, UnknownScene) {
  expectError("render --scene no-such-scene -t none " + kTiny, {"no-such-scene", "torus"});
}

TEST_F(CliTest, MalformedSceneFile) {
  write("bad.json", sceneJson(kLight, kObjects).substr(0, 60));
  expectError("render --scene bad.json -t none " + kTiny, {"bad.json", "JSON"});
}

TEST_F(CliTest, MissingMesh) {
  write("s.json", sceneJson(kLight, R"([{"name": "m", "mesh": "nope.obj"}])"));
  expectError("render --scene s.json -t none " + kTiny, {"s.json", "nope.obj"});
}

TEST_F(CliTest, DegenerateLight) {
  write("s.json", sceneJson(R"({"type": "sphere", "center": [0, 4, 0], "radius": 0})", kObjects));
  expectError("render --scene s.json -t none " + kTiny, {"s.json", "lights[0]", "radius"});
}

TEST_F(CliTest, NoLight) {
  write("s.json", sceneJson("", kObjects));
  for (const char* command : {"render -t none --out out", "compare --out out", "bench -t none --repeat 1"})
    expectError(std::string(command) + " --scene s.json --width 8 --height 8",
                {"scene 'tiny'", "has no light; add one to \"lights\""});
}

TEST_F(CliTest, LightIndexOutOfRange) {
  write("s.json", sceneJson(kLight, kObjects));
  expectError("render --scene s.json -t none --light 1 " + kTiny, {"--light 1", "has 1 light"});
  expectError("render --scene s.json -t none --light -1 " + kTiny, {"--light -1"});
}

TEST_F(CliTest, SceneFileTechniquesAreChecked) {
  write("typo.json", sceneJson(kLight, kObjects, R"(, "techniques": {"referense": {"spp": 2}})"));
  expectError("render --scene typo.json -t none " + kTiny, {"typo.json", "referense"});
  write("range.json", sceneJson(kLight, kObjects, R"(, "techniques": {"reference": {"spp": -2}})"));
  expectError("render --scene range.json -t none " + kTiny, {"range.json", "techniques.reference.spp", "-2"});
}

TEST_F(CliTest, UsageErrorsUseCli11Codes) {
  for (const std::string& args : {std::string("render"), std::string("render -t none --width 0"),
                                  std::string("frobnicate"), std::string("render -t none --no-such-flag")}) {
    const Result r = run(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.code, -1) << args;
    EXPECT_EQ(r.output.rfind("penumbra: error: ", 0), 0u) << args << "\n" << r.output;
  }
}

TEST_F(CliTest, HelpEverywhere) {
  for (const std::string sub : {"", "render", "compare", "bench", "scenes", "techniques"}) {
    const Result r = run(sub + " --help");
    EXPECT_EQ(r.code, 0) << sub << "\n" << r.output;
    EXPECT_NE(r.output.find("Usage:"), std::string::npos) << sub;
  }
  EXPECT_NE(run("render --help").output.find("--technique"), std::string::npos);
}

TEST_F(CliTest, NeverOverwritesTheSceneFile) {
  const std::string text = sceneJson(kLight, kObjects);
  write("s.json", text);
  expectError("bench --scene s.json -t none --repeat 1 --json s.json " + std::string("--width 8 --height 8"),
              {"refusing to write 's.json'", "input scene file"});
  // A scene file that happens to carry an output's name is refused too, before any work.
  write("tiny_none.png", text);
  expectError("render --scene tiny_none.png -t none --width 8 --height 8 --out .", {"refusing to write", "tiny_none.png"});
  EXPECT_EQ(read("s.json"), text);
  EXPECT_EQ(read("tiny_none.png"), text);
}

TEST_F(CliTest, ScenesListsBuiltins) {
  const Result r = run("scenes");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("torus "), std::string::npos) << r.output;
}

TEST_F(CliTest, TechniquesListsParameters) {
  const Result r = run("techniques");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.output.rfind("reference ", 0), 0u);  // the registry's order: the truth first
  for (const std::string name : {"none ", "raytraced-hard "})
    EXPECT_NE(r.output.find("\n" + name), std::string::npos) << name << "\n" << r.output;
  EXPECT_NE(r.output.find("--param spp (int, default"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("samples"), std::string::npos);
}

TEST_F(CliTest, RenderWritesPngAndExr) {
  const Result r = run("render --scene torus -t reference --threads 1 " + kTiny);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("visibility"), std::string::npos) << r.output;  // the pass timings
  ASSERT_TRUE(exists("out/torus_reference.png"));
  const std::string png = read("out/torus_reference.png");
  ASSERT_GT(png.size(), 24u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  // IHDR width and height, big-endian at bytes 16..23.
  auto be32 = [&](size_t at) {
    return (uint32_t(uint8_t(png[at])) << 24) | (uint32_t(uint8_t(png[at + 1])) << 16) |
           (uint32_t(uint8_t(png[at + 2])) << 8) | uint32_t(uint8_t(png[at + 3]));
  };
  EXPECT_EQ(be32(16), 32u);
  EXPECT_EQ(be32(20), 32u);
  const Image<float> v = readExr((dir_ / "out/torus_reference_v.exr").string());
  ASSERT_EQ(v.width(), 32);
  ASSERT_EQ(v.height(), 32);
  float lo = 1.0f, hi = 0.0f;
  for (float x : v) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  EXPECT_GE(lo, 0.0f);
  EXPECT_LE(hi, 1.0f);
  EXPECT_LT(lo, 0.5f);  // the torus casts a shadow into the frame
  EXPECT_EQ(hi, 1.0f);
}

TEST_F(CliTest, CommandLineParametersOverrideTheSceneFile) {
  write("s.json", sceneJson(kLight, kObjects, R"(, "techniques": {"reference": {"spp": 2}})"));
  const Result fromFile = run("render --scene s.json -t reference --width 8 --height 8 --out out");
  ASSERT_EQ(fromFile.code, 0) << fromFile.output;
  EXPECT_NE(fromFile.output.find("spp=2"), std::string::npos) << fromFile.output;
  const Result fromCli = run("render --scene s.json -t reference -p spp=3 --width 8 --height 8 --out out");
  ASSERT_EQ(fromCli.code, 0) << fromCli.output;
  EXPECT_NE(fromCli.output.find("spp=3"), std::string::npos) << fromCli.output;
  const Result fromShorthand = run("render --scene s.json -t reference --spp 5 --width 8 --height 8 --out out");
  EXPECT_NE(fromShorthand.output.find("spp=5"), std::string::npos) << fromShorthand.output;
}

TEST_F(CliTest, CompareWritesReportWithReferenceAndNone) {
  write("s.json", sceneJson(kLight, kObjects));
  const Result r = run("compare --scene s.json --techniques none,raytraced-hard " + kTiny);
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(exists("out/compare.json"));
  ASSERT_TRUE(exists("out/compare.md"));
  for (const std::string suffix : {".png", "_v.exr", "_v.png"}) {
    EXPECT_TRUE(exists("out/tiny_reference" + suffix)) << suffix;
    EXPECT_TRUE(exists("out/tiny_none" + suffix)) << suffix;
  }
  const nlohmann::json j = nlohmann::json::parse(read("out/compare.json"));
  const nlohmann::json* reference = nullptr;
  const nlohmann::json* none = nullptr;
  for (const auto& row : j["techniques"]) {
    if (row["name"] == "reference") reference = &row;
    if (row["name"] == "none") none = &row;
  }
  ASSERT_TRUE(reference && none) << j.dump(2);
  EXPECT_EQ(j["techniques"][0]["name"], "reference");  // the truth runs first
  EXPECT_LT(reference->at("rmse8").get<double>(), 1e-9);
  EXPECT_GT(none->at("rmse8").get<double>(), 1.0);  // a sphere over a plane: a real shadow in frame
  EXPECT_GT(none->at("rmse8").get<double>(), reference->at("rmse8").get<double>());
  EXPECT_TRUE(reference->at("stats").contains("mean_std_error")) << reference->dump(2);
  EXPECT_FALSE(j["baseline"].is_null());
  EXPECT_TRUE(none->at("ratio_to_baseline").is_number());
}

TEST_F(CliTest, EmptySceneRendersFullyLit) {
  write("empty.json", sceneJson(kLight, "[]"));
  for (const std::string technique : {"reference", "raytraced-hard"}) {
    const Result r = run("render --scene empty.json -t " + technique + " " + kTiny);
    ASSERT_EQ(r.code, 0) << technique << "\n" << r.output;
    const Image<float> v = readExr((dir_ / ("out/tiny_" + technique + "_v.exr")).string());
    ASSERT_EQ(v.size(), 32u * 32u);
    for (float x : v) ASSERT_EQ(x, 1.0f) << technique;
  }
}

TEST_F(CliTest, BenchPrintsRatiosAndWritesJson) {
  const Result r = run("bench --scene torus -t none,raytraced-hard --baseline raytraced-hard --repeat 2 --width 16 "
                       "--height 16 --json b.json");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("G-buffer raster"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(read("b.json"));
  EXPECT_EQ(j["kind"], "bench");
  EXPECT_EQ(j["baseline"], "raytraced-hard");
  bool found = false;
  for (const auto& row : j["techniques"]) {
    if (row["name"] != "raytraced-hard") continue;
    found = true;
    EXPECT_DOUBLE_EQ(row["ratio_to_baseline"].get<double>(), 1.0);
  }
  EXPECT_TRUE(found) << j.dump(2);
}

}  // namespace
}  // namespace penumbra
