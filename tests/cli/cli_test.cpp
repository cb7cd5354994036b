// End-to-end tests of the `penumbra` binary (apps/penumbra): every kind of bad input ends in one
// line "penumbra: error: ..." naming what is wrong and exit code 1 (CLI11 usage errors: its own
// non-zero code); render and compare write their files; compare's table measures `none` against
// the reference; compare's page (DIR/report/index.html) shows the numbers of the JSON beside it
// and only images that exist; a second compare reads the truth from the cache; --map-sizes runs
// the techniques with a map_size at each size. Tiny images (32 x 32, 4 spp) keep the whole file to
// a few seconds.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "eval/html_table.h"
#include "penumbra/image_io.h"
#include "penumbra/registry.h"

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
    for (const std::string& e : expected)
      EXPECT_NE(r.output.find(e), std::string::npos) << "missing '" << e << "' in: " << r.output;
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
  expectError("render --scene tiny_none.png -t none --width 8 --height 8 --out .",
              {"refusing to write", "tiny_none.png"});
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
  // Each technique says how it treats the light shapes, a concave polygon included.
  for (const TechniqueInfo& info : techniqueRegistry())
    EXPECT_NE(r.output.find("\n  lights: " + info.lights + "\n"), std::string::npos) << info.name << "\n" << r.output;
}

// docs/techniques.md lists every parameter as `penumbra techniques` prints it (the schema is the one
// source; the page must follow it): "--param NAME REST" there is "- `NAME` REST" in the page.
TEST_F(CliTest, TheTechniquesPageListsEveryParameterAsTheSchemaHasIt) {
  const Result r = run("techniques");
  ASSERT_EQ(r.code, 0);
  std::ifstream in(std::string(PENUMBRA_SOURCE_DIR) + "/docs/techniques.md");
  std::stringstream page;
  page << in.rdbuf();
  ASSERT_FALSE(page.str().empty());
  std::istringstream lines(r.output);
  std::string line;
  size_t checked = 0;
  const std::string marker = "  --param ";
  while (std::getline(lines, line)) {
    if (line.rfind(marker, 0) != 0) continue;
    const std::string rest = line.substr(marker.size());
    const size_t space = rest.find(' ');
    const std::string expected = "- `" + rest.substr(0, space) + "`" + rest.substr(space);
    EXPECT_NE(page.str().find(expected + "\n"), std::string::npos) << "docs/techniques.md lacks or differs on:\n"
                                                                   << expected;
    ++checked;
  }
  EXPECT_GT(checked, 50u);
  // Its table of techniques names each one's source as the registry does.
  for (const TechniqueInfo& info : techniqueRegistry())
    EXPECT_NE(page.str().find("| `" + info.name + "` | " + info.source + " |"), std::string::npos) << info.name;
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
  for (const std::string file : {"index.html", "compare.json", "compare.md", "scene.json"})
    ASSERT_TRUE(exists("out/report/" + file)) << file;
  for (const std::string suffix : {".png", "_v.exr", "_v.png"}) {
    EXPECT_TRUE(exists("out/report/tiny_truth" + suffix)) << suffix;
    EXPECT_TRUE(exists("out/report/tiny_none" + suffix)) << suffix;
  }
  EXPECT_TRUE(exists("out/report/tiny_none_err.png"));
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  const nlohmann::json* none = nullptr;
  for (const auto& row : j["techniques"])
    if (row["name"] == "none") none = &row;
  ASSERT_TRUE(none) << j.dump(2);
  EXPECT_EQ(j["truth"]["name"], "reference");
  EXPECT_EQ(j["truth"]["params"]["spp"], "4");  // --spp sets the truth
  // The times say what they are: a first frame each, the shared Embree scene's build apart.
  EXPECT_NE(j["settings"]["timings"].get<std::string>().find("its first"), std::string::npos) << j["settings"];
  EXPECT_GE(std::stod(j["settings"]["ray_scene_ms"].get<std::string>()), 0.0);
  EXPECT_LT(j["truth"]["rmse8"].get<double>(), 1e-9);
  EXPECT_GT(none->at("rmse8").get<double>(), 1.0);  // a sphere over a plane: a real shadow in frame
  EXPECT_TRUE(j["truth"]["stats"].contains("mean_std_error")) << j["truth"].dump(2);
  EXPECT_FALSE(j["baseline"].is_null());
  EXPECT_TRUE(none->at("ratio_to_baseline").is_number());
  // The scene written beside the page is the scene that was rendered.
  EXPECT_NE(read("out/report/scene.json").find("\"tiny\""), std::string::npos);
}

// A sequence (--motion-path, or the scene file's "motion"): per frame the truth and each technique, a
// row's error averaged over the frames, its temporal error against the truth's sequence, the truth's
// noise floor; a technique that follows the truth exactly (a reference row with the truth's own
// parameters) has no flicker at all.
TEST_F(CliTest, CompareOverASequenceReportsFlickerAndTheNoiseFloor) {
  write("s.json", sceneJson(kLight, kObjects));
  const Result r =
      run("compare --scene s.json --techniques reference,raytraced-hard,hard --motion-path '0,4,0;0.3,4,0' "
          "--frames 3 " +
          kTiny);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("over 3 frames (light 0 along (0, 4, 0) -> (0.3, 4, 0))"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  ASSERT_TRUE(j.contains("sequence")) << j.dump(2);
  EXPECT_EQ(j["sequence"]["frames"], 3);
  EXPECT_EQ(j["sequence"]["noise_floor_seeds"], "seeds 1 and 2");
  EXPECT_GT(j["sequence"]["noise_floor"]["flicker"].get<double>(), 0.0);  // 4 spp: plenty of noise
  EXPECT_EQ(j["sequence"]["noise_floor"]["frame_pairs"], 2);
  for (const auto& row : j["techniques"]) {
    ASSERT_TRUE(row.contains("sequence")) << row.dump(2);
    const auto& frames = row["sequence"]["frames"];
    ASSERT_EQ(frames.size(), 3u);
    double mean = 0.0;
    for (const auto& f : frames) {
      mean += f["rmse8"].get<double>() / 3.0;
      for (const auto& [kind, file] : f["images"].items())
        EXPECT_TRUE(exists("out/report/" + file.get<std::string>())) << file;
    }
    EXPECT_NEAR(row["rmse8"].get<double>(), mean, 1e-9) << row["name"];
    if (row["name"] == "reference") {
      EXPECT_EQ(row["sequence"]["temporal"]["flicker"].get<double>(), 0.0);
    } else {
      EXPECT_GT(row["sequence"]["temporal"]["flicker"].get<double>(), 0.0) << row["name"];
    }
  }
  // Each frame's truth is cached on its own: a second run reuses all three and gives the same numbers.
  const Result again =
      run("compare --scene s.json --techniques reference,raytraced-hard,hard --motion-path "
          "'0,4,0;0.3,4,0' --frames 3 " +
          kTiny);
  ASSERT_EQ(again.code, 0) << again.output;
  size_t reused = 0;
  for (size_t at = again.output.find("truth: reused"); at != std::string::npos;
       at = again.output.find("truth: reused", at + 1))
    ++reused;
  EXPECT_EQ(reused, 6u) << again.output;  // 3 frames x (the truth and the noise floor's)
  const nlohmann::json second = nlohmann::json::parse(read("out/report/compare.json"));
  ASSERT_EQ(second["techniques"].size(), j["techniques"].size());
  for (size_t i = 0; i < j["techniques"].size(); ++i) {  // the same V, so the same errors (not the same times)
    EXPECT_EQ(second["techniques"][i]["rmse8"], j["techniques"][i]["rmse8"]);
    EXPECT_EQ(second["techniques"][i]["sequence"], j["techniques"][i]["sequence"]);
  }
  EXPECT_EQ(second["sequence"], j["sequence"]);

  // The scene file's motion, and bad motions named.
  write("m.json", sceneJson(kLight, kObjects,
                            R"(, "motion": {"moves": "camera", "path": [[0, 3, 5], [0.5, 3, 5]], "frames": 2})"));
  const Result camera = run("compare --scene m.json --techniques raytraced-hard " + kTiny);
  ASSERT_EQ(camera.code, 0) << camera.output;
  EXPECT_NE(camera.output.find("over 2 frames (the camera along (0, 3, 5) -> (0.5, 3, 5))"), std::string::npos)
      << camera.output;
  expectError("compare --scene s.json --techniques hard --motion-path '0,4,0;1,4' " + kTiny,
              {"--motion-path: key 1 '1,4' is not three numbers x,y,z"});
  expectError("compare --scene s.json --techniques hard --motion-path '0,4,0;0,4,0' " + kTiny,
              {"--motion-path: path has zero length"});
  expectError("compare --scene s.json --techniques hard --frames 4 " + kTiny,
              {"--frames 4: the scene has no motion; give one with --motion-path"});
  expectError("compare --scene s.json --techniques hard --motion-path '0,4,0;1,4,0' --map-sizes 16 " + kTiny,
              {"--map-sizes is for a still scene"});
}

std::map<std::string, std::vector<std::string>> pageTable(const std::string& html) {
  return testing::htmlTableValues(html);
}

TEST_F(CliTest, ComparePageShowsTheJsonNumbers) {
  write("s.json", sceneJson(kLight, kObjects));
  const Result r =
      run("compare --scene s.json --techniques reference,none,raytraced-hard,hard -p reference.spp=2 "
          "--map-sizes 32,16 " +
          kTiny);
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  const std::string html = read("out/report/index.html");
  const auto table = pageTable(html);
  ASSERT_EQ(table.size(), 4u) << html;
  const char* keys[] = {"rmse8",      "penumbra_rmse8", "max_abs_error", "umbra_leaks",      "speckle",
                        "prepare_ms", "visibility_ms",  "total_ms",      "ratio_to_baseline"};
  for (const auto& row : j["techniques"]) {
    const auto it = table.find(row["label"].get<std::string>());
    ASSERT_NE(it, table.end()) << row["label"] << "\n" << html;
    ASSERT_EQ(it->second.size(), 1 + std::size(keys));
    for (size_t k = 0; k < std::size(keys); ++k)
      EXPECT_DOUBLE_EQ(std::stod(it->second[k + 1]), row[keys[k]].get<double>()) << row["label"] << " " << keys[k];
    // Every image the page shows exists beside it.
    for (const auto& [kind, file] : row["images"].items())
      EXPECT_TRUE(exists("out/report/" + file.get<std::string>())) << file;
  }
  const std::regex srcRe("<img src=\"([^\"]*)\"");
  size_t images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), srcRe); it != std::sregex_iterator(); ++it, ++images)
    EXPECT_TRUE(exists("out/report/" + (*it)[1].str())) << (*it)[1];
  EXPECT_EQ(images, 2u + 4u * 4u);  // the truth's two, then per row: truth shaded, shaded, V, error

  // The reference row is a technique with its own samples, measured against the 4-spp truth.
  const auto& referenceRow = j["techniques"][0];
  EXPECT_EQ(referenceRow["label"], "reference (2 spp)");
  EXPECT_EQ(referenceRow["params"]["spp"], "2");
  EXPECT_GT(referenceRow["rmse8"].get<double>(), 0.0);  // 2 vs 4 samples: noise differs
  EXPECT_EQ(j["truth"]["params"]["spp"], "4");

  // --map-sizes: sorted; `hard` ran at each size, the others once and repeated.
  EXPECT_EQ(j["map_sizes"], nlohmann::json::array({16, 32}));
  for (const auto& row : j["techniques"]) {
    ASSERT_EQ(row["map_size_sweep"].size(), 2u) << row["name"];
    const double a = row["map_size_sweep"][0]["rmse8"], b = row["map_size_sweep"][1]["rmse8"];
    EXPECT_EQ(row["map_size_varies"].get<bool>(), row["name"] == "hard") << row["name"];
    if (row["name"] == "hard")
      EXPECT_NE(a, b);  // a 16^2 and a 32^2 map do not cast the same shadow
    else
      EXPECT_EQ(a, b);
  }
  const std::string md = read("out/report/compare.md");
  EXPECT_NE(md.find("| technique | 16 | 32 |"), std::string::npos) << md;
  // The profile: one value per column of the chosen row, for the truth and every row.
  const int row = j["profile"]["row"];
  EXPECT_GE(row, 0);
  EXPECT_LT(row, 32);
  EXPECT_EQ(j["profile"]["reference"].size(), 32u);
  for (const auto& t : j["techniques"]) EXPECT_EQ(t["profile"].size(), 32u);
  EXPECT_NE(html.find("id=\"plot-map-size\""), std::string::npos);
}

TEST_F(CliTest, CompareReusesTheCachedTruth) {
  write("s.json", sceneJson(kLight, kObjects));
  const std::string args = "compare --scene s.json --techniques none " + kTiny;
  const Result first = run(args);
  ASSERT_EQ(first.code, 0) << first.output;
  EXPECT_NE(first.output.find("truth: rendering"), std::string::npos) << first.output;
  const std::string truthV = read("out/report/tiny_truth_v.exr");
  const nlohmann::json j1 = nlohmann::json::parse(read("out/report/compare.json"));
  EXPECT_FALSE(j1["truth"].contains("cached"));

  const Result second = run(args);
  ASSERT_EQ(second.code, 0) << second.output;
  EXPECT_NE(second.output.find("truth: reused"), std::string::npos) << second.output;
  EXPECT_EQ(second.output.find("truth: rendering"), std::string::npos) << second.output;
  const nlohmann::json j2 = nlohmann::json::parse(read("out/report/compare.json"));
  EXPECT_TRUE(j2["truth"]["cached"].get<bool>());
  EXPECT_EQ(read("out/report/tiny_truth_v.exr"), truthV);
  // The timings and stats are those of the run that rendered it, not of reading the file.
  EXPECT_EQ(j2["truth"]["total_ms"], j1["truth"]["total_ms"]);
  EXPECT_EQ(j2["truth"]["stats"], j1["truth"]["stats"]);
  EXPECT_EQ(j2["techniques"][0]["rmse8"], j1["techniques"][0]["rmse8"]);

  // Anything the truth depends on is part of the key: another sample count or image size renders again.
  for (const std::string& other :
       {std::string("--spp 5 --width 32 --height 32"), std::string("--spp 4 --width 32 --height 16")}) {
    const Result r = run("compare --scene s.json --techniques none --out out " + other);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NE(r.output.find("truth: rendering"), std::string::npos) << other << "\n" << r.output;
  }
  // So does a change of the scene itself.
  write("s.json", sceneJson(R"({"type": "sphere", "center": [0, 4.5, 0], "radius": 0.5})", kObjects));
  const Result moved = run(args);
  EXPECT_NE(moved.output.find("truth: rendering"), std::string::npos) << moved.output;
  const Result noCache = run(args + " --no-cache");
  EXPECT_NE(noCache.output.find("truth: rendering"), std::string::npos) << noCache.output;
  const Result elsewhere = run(args + " --cache-dir shared-cache");
  ASSERT_EQ(elsewhere.code, 0) << elsewhere.output;
  size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(dir_ / "shared-cache")) entries += entry.path().extension() == ".exr";
  EXPECT_EQ(entries, 1u);
  // A damaged entry is rendered anew, not trusted.
  for (const auto& entry : fs::directory_iterator(dir_ / "out/cache"))
    if (entry.path().extension() == ".json") std::ofstream(entry.path()) << "{";
  const Result damaged = run(args);
  ASSERT_EQ(damaged.code, 0) << damaged.output;
  EXPECT_NE(damaged.output.find("cannot be read"), std::string::npos) << damaged.output;
}

TEST_F(CliTest, CompareOptionsAreChecked) {
  write("s.json", sceneJson(kLight, kObjects));
  expectError("compare --scene s.json --techniques none --profile-row 32 " + kTiny, {"--profile-row 32", "0 to 31"});
  expectError("compare --scene s.json --techniques none -p reference.spp=2 " + kTiny, {"reference.spp=2", "--spp"});
  expectError("compare --scene s.json --techniques hard --map-sizes 16,3 " + kTiny, {"map_size", "3", "--map-sizes"});
  const Result r = run("compare --scene s.json --techniques none --profile-row 7 " + kTiny);
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  EXPECT_EQ(j["profile"]["row"], 7);
  EXPECT_EQ(j["profile"]["choice"], "--profile-row");
  EXPECT_NE(j["command"].get<std::string>().find("--profile-row 7"), std::string::npos);
}

// `-p '*.key=value'` sets the key for every technique run that has it, a technique's own
// `name.key=value` overrides it, and a key that none of them has is refused.
TEST_F(CliTest, CompareWildcardParameterSetsEveryTechniqueThatHasTheKey) {
  write("s.json", sceneJson(kLight, kObjects));
  const Result r =
      run("compare --scene s.json --techniques hard,pcf,raytraced-hard -p '*.map_fit=stable' -p pcf.map_fit=tight " +
          kTiny);
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  std::map<std::string, nlohmann::json> params;
  for (const auto& row : j["techniques"]) params[row["name"].get<std::string>()] = row["params"];
  EXPECT_EQ(params["hard"]["map_fit"], "stable") << j.dump(2);
  EXPECT_EQ(params["pcf"]["map_fit"], "tight");
  EXPECT_FALSE(params["raytraced-hard"].contains("map_fit"));
  expectError(
      "compare --scene s.json --techniques raytraced-hard,none --baseline raytraced-hard -p '*.map_fit=stable' " +
          kTiny,
      {"*.map_fit=stable", "none of the techniques run here has a parameter 'map_fit'"});
  expectError("compare --scene s.json --techniques hard -p '*.map_fit=loose' " + kTiny, {"map_fit", "loose"});
}

// In compare and bench --spp is the reference's (the truth's too): raytraced-soft and hybrid have an
// `spp` of 1 to 16 rays, which the truth's thousands must neither set nor fail on; theirs is set with
// --param. In render, the one technique run takes it.
TEST_F(CliTest, SppIsTheReferencesWhereSeveralTechniquesRun) {
  write("s.json", sceneJson(kLight, kObjects));
  const Result r =
      run("compare --scene s.json --techniques reference,raytraced-soft,hybrid -p hybrid.spp=3 --width 16 --height 16 "
          "--spp 300 --out out");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  std::map<std::string, nlohmann::json> params;
  for (const auto& row : j["techniques"]) params[row["name"].get<std::string>()] = row["params"];
  EXPECT_EQ(params["reference"]["spp"], "300") << j.dump(2);
  EXPECT_EQ(params["raytraced-soft"]["spp"], "2");  // its default
  EXPECT_EQ(params["hybrid"]["spp"], "3");
  const Result b =
      run("bench --scene s.json --techniques raytraced-soft,reference --repeat 1 --width 16 --height 16 "
          "--spp 300");
  EXPECT_EQ(b.code, 0) << b.output;
  expectError("render --scene s.json -t raytraced-soft --width 16 --height 16 --spp 300 --out r",
              {"raytraced-soft.spp = 300", "[1, 16]"});
}

// With no --techniques every registered technique runs; one that does not support the light's shape
// is listed with its reason instead of ending the comparison, and fails when asked for by name.
TEST_F(CliTest, CompareListsEveryRegisteredTechnique) {
  write("s.json", sceneJson(kLight, kObjects));
  const Result r = run("compare --scene s.json --width 24 --height 24 --spp 2 --out out");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  std::set<std::string> seen;
  for (const auto& row : j["techniques"]) seen.insert(row["name"].get<std::string>());
  std::string skippedName;
  if (j.contains("skipped"))
    for (const auto& s : j["skipped"]) {
      seen.insert(s["name"].get<std::string>());
      EXPECT_NE(s["reason"].get<std::string>().find("sphere"), std::string::npos) << s.dump();
      skippedName = s["name"];
    }
  for (const TechniqueInfo& info : techniqueRegistry()) EXPECT_TRUE(seen.count(info.name)) << info.name;
  EXPECT_EQ(seen.size(), techniqueRegistry().size());
  ASSERT_FALSE(skippedName.empty()) << "the scene's sphere light should be one some technique refuses";
  // The default set skipped it for a stated reason: not a failure, and its row says why in every writer.
  EXPECT_NE(read("out/report/compare.md").find("| " + skippedName + " |"), std::string::npos);
  EXPECT_NE(read("out/report/compare.md").find("not run here: "), std::string::npos);
  EXPECT_NE(read("out/report/index.html").find("<tr data-not-run=\"" + skippedName + "\">"), std::string::npos);
  EXPECT_NE(r.output.find(skippedName + ": not run here: "), std::string::npos) << r.output;

  // Named beside others, it costs its row only: the others run, the report is written, and the exit
  // status (after the report) says which named technique did not run.
  fs::remove_all(dir_ / "out");
  const Result named = run("compare --scene s.json --techniques hard," + skippedName + ",pcf " + kTiny);
  EXPECT_EQ(named.code, 1) << named.output;
  EXPECT_NE(named.output.find("penumbra: error: a technique asked for did not run on this scene (the reasons are in "
                              "the report): " +
                              skippedName),
            std::string::npos)
      << named.output;
  ASSERT_TRUE(fs::exists(dir_ / "out/report/index.html")) << named.output;
  const nlohmann::json k = nlohmann::json::parse(read("out/report/compare.json"));
  std::set<std::string> ran;
  for (const auto& row : k["techniques"]) ran.insert(row["name"].get<std::string>());
  EXPECT_EQ(ran, (std::set<std::string>{"hard", "pcf"}));
  ASSERT_EQ(k["skipped"].size(), 1u);
  EXPECT_EQ(k["skipped"][0]["name"], skippedName);
  EXPECT_NE(k["skipped"][0]["reason"].get<std::string>().find("sphere"), std::string::npos);

  // bench alike: the row says why, the others are timed, and a named one fails the run.
  const Result bench =
      run("bench --scene s.json --techniques hard," + skippedName + " --repeat 1 --width 32 --height 32");
  EXPECT_EQ(bench.code, 1) << bench.output;
  EXPECT_NE(bench.output.find(skippedName + ": not run here: "), std::string::npos) << bench.output;
  EXPECT_NE(bench.output.find("hard "), std::string::npos) << bench.output;
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
  const Result r =
      run("bench --scene torus -t none,raytraced-hard --baseline raytraced-hard --repeat 2 --width 16 "
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

// bench over a sequence: one technique instance across the frames; the times are steady frames (the
// median over frames 2 to N) and the first frame's total is reported apart, as the table says.
TEST_F(CliTest, BenchOverASequenceSeparatesTheFirstFrame) {
  const Result r =
      run("bench --scene torus -t hard,raytraced-hard --width 16 --height 16 --motion-path '0.4,8,-1;0.6,8,-1' "
          "--frames 3 --json b.json");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames: light 0 along (0.4, 8, -1) -> (0.6, 8, -1)"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("b.json"));
  EXPECT_EQ(j["settings"]["frames"], "3");
  EXPECT_NE(j["settings"]["statistic"].get<std::string>().find("steady frames"), std::string::npos);
  ASSERT_EQ(j["techniques"].size(), 2u) << j.dump(2);
  for (const auto& row : j["techniques"]) {
    ASSERT_TRUE(row["stats"].contains("first_frame_ms")) << row.dump(2);
    EXPECT_GT(row["stats"]["first_frame_ms"].get<double>(), 0.0);
    EXPECT_GT(row["total_ms"].get<double>(), 0.0);
  }
  expectError("bench --scene torus -t hard --repeat 2 --motion-path '0,8,0;1,8,0'",
              {"--repeat is for a still scene; over a sequence each of the 12 frames runs once"});
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// A scene JSON like sceneJson's, with the given (JSON-escaped) name.
std::string namedScene(const std::string& escapedName) {
  return "{\"name\": \"" + escapedName + "\", " + kCamera + ", \"lights\": [" + kLight + "], \"objects\": " + kObjects +
         "}";
}

std::vector<std::string> filesUnder(const fs::path& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) files.push_back(fs::relative(e.path(), dir).string());
  std::sort(files.begin(), files.end());
  return files;
}

// A scene's name is text anyone may write: output names are a slug of it, never a path.
TEST_F(CliTest, SceneNamesNeverBecomePaths) {
  fs::create_directories(dir_ / "work");
  write("victim.txt", "keep");
  write("work/rock.obj", "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n");
  const std::pair<std::string, std::string> cases[] = {
      {"../escaped", "_escaped_none.png"},          // a relative path
      {"/tmp/absolute", "_tmp_absolute_none.png"},  // an absolute one
      {"rock.obj\\u0000", "rock.obj__none.png"},    // a NUL that cut the suffix off
      {"../victim.txt\\u0000", "_victim.txt__none.png"},
      {"a#b?c%d e", "a_b_c_d_e_none.png"},  // characters that break a URL
  };
  for (const auto& [name, expected] : cases) {
    SCOPED_TRACE(name);
    write("work/s.json", namedScene(name));
    fs::remove_all(dir_ / "work/o");
    const Result r = run("render --scene work/s.json -t none --width 8 --height 8 --out work/o");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(exists("work/o/" + expected)) << r.output;
    EXPECT_EQ(filesUnder(dir_ / "work/o").size(), 2u) << r.output;  // the PNG and the EXR, nothing else
  }
  EXPECT_EQ(read("victim.txt"), "keep");
  EXPECT_EQ(read("work/rock.obj"), "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n");
  EXPECT_FALSE(exists("escaped_none.png"));
  // In compare every image gets its own name, and the page's links work.
  write("work/s.json", namedScene("x#y\\u0000"));
  const Result c = run("compare --scene work/s.json -t hard --width 8 --height 8 --spp 2 --out work/c");
  ASSERT_EQ(c.code, 0) << c.output;
  EXPECT_TRUE(exists("work/c/report/x_y__hard.png")) << c.output;
  EXPECT_TRUE(exists("work/c/report/x_y__truth_v.exr")) << c.output;
  // --name sets the stem, made safe the same way.
  const Result n = run("render --scene work/s.json -t none --width 8 --height 8 --name ../mine --out work/n");
  ASSERT_EQ(n.code, 0) << n.output;
  EXPECT_TRUE(exists("work/n/_mine_none.png")) << n.output;
}

// An input file is never a write target, whatever it is called (compared by identity).
TEST_F(CliTest, InputMeshesAreNeverReplaced) {
  const std::string mesh = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n";
  write("tiny_none.png", mesh);  // a mesh file that carries an output's name
  write("s.json", "{\"name\": \"tiny\", " + kCamera + ", \"lights\": [" + kLight +
                      "], \"objects\": [{\"name\": \"m\", \"mesh\": \"tiny_none.png\"}]}");
  const Result r = run("render --scene s.json -t none --width 8 --height 8 --out .");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("refusing to write"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("an input file"), std::string::npos) << r.output;
  EXPECT_EQ(read("tiny_none.png"), mesh);
}

// Outputs are written beside their target and renamed into place: a link is replaced itself (its
// target untouched), a read-only file is refused, and nothing half-written is left at the name.
TEST_F(CliTest, OutputsAreNotWrittenThroughLinksOrOverReadOnlyFiles) {
  write("s.json", sceneJson(kLight, kObjects));
  write("victim.txt", "keep");
  fs::create_directories(dir_ / "o");
  fs::create_symlink(dir_ / "victim.txt", dir_ / "o/tiny_none.png");
  const Result r = run("render --scene s.json -t none --width 8 --height 8 --out o");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(read("victim.txt"), "keep");
  EXPECT_FALSE(fs::is_symlink(dir_ / "o/tiny_none.png"));
  EXPECT_EQ(read("o/tiny_none.png").rfind("\x89PNG", 0), 0u);
  fs::permissions(dir_ / "o/tiny_none_v.exr", fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  const std::string before = read("o/tiny_none_v.exr");
  const Result ro = run("render --scene s.json -t none --width 8 --height 8 --out o");
  EXPECT_EQ(ro.code, 1) << ro.output;
  EXPECT_NE(ro.output.find("read-only"), std::string::npos) << ro.output;
  EXPECT_EQ(read("o/tiny_none_v.exr"), before);
  for (const std::string& f : filesUnder(dir_ / "o")) EXPECT_EQ(f.find(".partial-"), std::string::npos) << f;
}

// Two compare runs into one folder: the second is refused at once instead of mixing the reports.
TEST_F(CliTest, ACompareFolderInUseIsRefused) {
  write("s.json", sceneJson(kLight, kObjects));
  fs::create_directories(dir_ / "out");
  const int fd = ::open((dir_ / "out/.penumbra.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);  // as a running compare holds it
  expectError("compare --scene s.json -t hard " + kTiny, {"is in use by another penumbra run", ".penumbra.lock"});
  ::close(fd);
  const Result r = run("compare --scene s.json -t hard " + kTiny);
  EXPECT_EQ(r.code, 0) << r.output;
}

// An interrupted compare leaves the previous report whole: the page, its JSON and its images from
// one run, and the new run's files only in a folder that says it is partial.
TEST_F(CliTest, AnInterruptedCompareLeavesThePreviousReportWhole) {
  write("s.json", sceneJson(kLight, kObjects));
  ASSERT_EQ(run("compare --scene s.json -t hard,pcf " + kTiny).code, 0);
  const std::string html = read("out/report/index.html"), json = read("out/report/compare.json");
  const std::vector<std::string> files = filesUnder(dir_ / "out/report");
  // A truth of many samples takes seconds; interrupt it once its staging folder exists.
  const std::string command = "cd '" + dir_.string() +
                              "' && exec '" PENUMBRA_CLI
                              "' compare --scene s.json -t hard --width 256 --height 256 --spp 65536 --out out "
                              ">/dev/null 2>&1";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bool staged = false;
  for (int i = 0; i < 600 && !staged; ++i) {
    for (const auto& e : fs::directory_iterator(dir_ / "out"))
      staged = staged || e.path().filename().string().rfind(".report-partial-", 0) == 0;
    if (!staged) ::usleep(10000);
  }
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(staged);
  EXPECT_EQ(read("out/report/index.html"), html);
  EXPECT_EQ(read("out/report/compare.json"), json);
  EXPECT_EQ(filesUnder(dir_ / "out/report"), files);
}

// The cache checks the image it reads: another technique's V copied over the cached truth is
// caught (by the key and pixel checksum in the EXR's header) and the truth rendered anew.
TEST_F(CliTest, TheCacheDoesNotTrustAnEditedImage) {
  write("s.json", sceneJson(kLight, kObjects));
  ASSERT_EQ(run("compare --scene s.json -t hard " + kTiny).code, 0);
  const Result again = run("compare --scene s.json -t hard " + kTiny);
  ASSERT_NE(again.output.find("truth: reused"), std::string::npos) << again.output;
  std::string cached;
  for (const auto& e : fs::directory_iterator(dir_ / "out/cache"))
    if (e.path().extension() == ".exr") cached = e.path().string();
  ASSERT_FALSE(cached.empty());
  fs::copy_file(dir_ / "out/report/tiny_hard_v.exr", cached, fs::copy_options::overwrite_existing);
  const Result edited = run("compare --scene s.json -t hard " + kTiny);
  ASSERT_EQ(edited.code, 0) << edited.output;
  EXPECT_NE(edited.output.find("truth: rendering reference"), std::string::npos) << edited.output;
  EXPECT_NE(edited.output.find("its image was not written for this key"), std::string::npos) << edited.output;
  const nlohmann::json j = nlohmann::json::parse(read("out/report/compare.json"));
  EXPECT_GT(j["techniques"][0]["rmse8"].get<double>(), 0.0);
  // A cache folder that cannot be made is a warning: the report is still written.
  write("plain.txt", "a file, not a folder");
  const Result uncached =
      run("compare --scene s.json -t hard --cache-dir plain.txt/cache --width 32 --height 32 --spp 4 --out out2");
  EXPECT_EQ(uncached.code, 0) << uncached.output;
  EXPECT_NE(uncached.output.find("penumbra: warning: "), std::string::npos) << uncached.output;
  EXPECT_TRUE(exists("out2/report/index.html")) << uncached.output;
  // ... said before the truth is rendered, not after.
  EXPECT_LT(uncached.output.find("penumbra: warning: "), uncached.output.find("truth: rendering")) << uncached.output;
}

// The reproductions of runs too large for the machine: refused before any work (no G-buffer, no
// output), naming the technique, the parameters that set the estimate and --force. The estimates
// agree with the sizes worked out by hand: 1024 maps of 8192^2 four-byte depths are 256 GiB; 65
// sample points of heidrich at 8192^2 hold about 170 GB.
TEST_F(CliTest, RunsTooLargeForTheMachineAreRefusedUpFront) {
  const Result multisample = run("render --scene torus -t multisample -p samples=1024 -p map_size=8192 --out o");
  EXPECT_EQ(multisample.code, 1) << multisample.output;
  EXPECT_NE(multisample.output.find("multisample needs about 256.5 GiB"), std::string::npos) << multisample.output;
  EXPECT_NE(multisample.output.find("map_size=8192, samples=1024"), std::string::npos) << multisample.output;
  EXPECT_NE(multisample.output.find("--force"), std::string::npos) << multisample.output;
  EXPECT_EQ(multisample.output.find("scene torus"), std::string::npos)
      << "refused after starting work: " << multisample.output;
  EXPECT_FALSE(exists("o")) << "nothing is written for a refused run";

  const Result heidrich = run("render --scene linear -t heidrich -p subdivisions=64 -p map_size=8192 --out o");
  EXPECT_EQ(heidrich.code, 1) << heidrich.output;
  EXPECT_NE(heidrich.output.find("heidrich needs about 162.5 GiB"), std::string::npos) << heidrich.output;

  // Rays: the time budget. compare counts the truth and every row.
  const Result rays = run("render --scene torus -t reference --width 8192 --height 8192 --spp 65536 --out o");
  EXPECT_EQ(rays.code, 1) << rays.output;
  EXPECT_NE(rays.output.find("4.4e+12 shadow rays"), std::string::npos) << rays.output;
  EXPECT_NE(rays.output.find("spp=65536"), std::string::npos) << rays.output;
  const Result truth = run("compare --scene torus -t hard --width 8192 --height 8192 --spp 4096 --out c");
  EXPECT_EQ(truth.code, 1) << truth.output;
  EXPECT_NE(truth.output.find("the most by reference (8192 x 8192 pixels x spp=4096)"), std::string::npos)
      << truth.output;
  EXPECT_EQ(truth.output.find("truth: rendering"), std::string::npos) << truth.output;
  const Result bench = run("bench --scene torus -t reference --spp 65536 --width 1024 --height 1024 --repeat 5");
  EXPECT_EQ(bench.code, 1) << bench.output;
  EXPECT_NE(bench.output.find("shadow rays"), std::string::npos) << bench.output;

  // Within the machine and the budget, --force changes nothing.
  const Result forced = run("render --scene torus -t hard --width 32 --height 32 --force --out o");
  EXPECT_EQ(forced.code, 0) << forced.output;
  EXPECT_EQ(forced.output.find("warning"), std::string::npos) << forced.output;
}

// Mesh files are size-checked before import, with a limit the user can raise.
TEST_F(CliTest, MeshFilesAreSizeCheckedBeforeImport) {
  std::string obj = "v 0 1 0\nv 1 1 0\nv 0 1 1\n";
  while (obj.size() < 4096) obj += "# padding to make the file a few KiB\n";
  obj += "f 1 2 3\n";
  write("tri.obj", obj);
  write("m.json", sceneJson(kLight, R"([{"name": "ground", "primitive": {"type": "plane", "size": [4, 4]}},
    {"name": "tri", "mesh": "tri.obj"}])"));
  const Result refused = run("render --scene m.json -t hard --width 16 --height 16 --max-mesh-size 0.002 --out o");
  EXPECT_EQ(refused.code, 1) << refused.output;
  EXPECT_NE(refused.output.find("tri.obj: the mesh file is " + std::to_string(obj.size()) +
                                " bytes, over the limit of 2097 bytes"),
            std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("--max-mesh-size"), std::string::npos) << refused.output;
  const Result raised = run("render --scene m.json -t hard --width 16 --height 16 --max-mesh-size 1 --out o");
  EXPECT_EQ(raised.code, 0) << raised.output;
  // A file over the default limit (1 GiB; sparse, so it costs no disk) is refused at once, unread.
  {
    std::ofstream big(dir_ / "big.obj");
    big.seekp((std::streamoff{1} << 30) + 1);
    big << '\n';
  }
  write("big.json", sceneJson(kLight, R"([{"name": "big", "mesh": "big.obj"}])"));
  const Result big = run("render --scene big.json -t hard --width 16 --height 16 --out o");
  EXPECT_EQ(big.code, 1) << big.output;
  EXPECT_NE(
      big.output.find("big.obj: the mesh file is 1073741826 bytes, over the limit of 1073741824 bytes (1024 MiB)"),
      std::string::npos)
      << big.output;
}

// Errors that can be known before rendering are reported before rendering: an output folder that
// cannot be made, a bench JSON path in a missing folder.
TEST_F(CliTest, OutputErrorsComeBeforeTheWork) {
  write("plain.txt", "a file, not a folder");
  const Result render = run("render --scene torus -t reference --width 32 --height 32 --out plain.txt/o");
  EXPECT_EQ(render.code, 1) << render.output;
  EXPECT_NE(render.output.find("cannot create output directory 'plain.txt/o'"), std::string::npos) << render.output;
  EXPECT_EQ(render.output.find("technique reference"), std::string::npos) << "rendered first: " << render.output;
  const Result bench = run("bench --scene torus -t hard --width 32 --height 32 --repeat 1 --json missing/b.json");
  EXPECT_EQ(bench.code, 1) << bench.output;
  EXPECT_NE(bench.output.find("the folder 'missing' does not exist"), std::string::npos) << bench.output;
  EXPECT_EQ(bench.output.find("scene torus"), std::string::npos) << "benchmarked first: " << bench.output;
}

// A still scene too: the first of --repeat runs is reported apart (first_frame_ms, the G-buffer's
// first time), and so is each technique's storage made before it (setup_ms); the times are the median of the others
// (issue: a first and a steady frame are different numbers, and the table says which it shows).
TEST_F(CliTest, BenchOnAStillSceneSeparatesTheFirstFrame) {
  const Result r = run("bench --scene torus -t hard,plm --width 32 --height 32 --repeat 3 --json s.json");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("ms steady (median of 2),"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ms first"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read("s.json"));
  EXPECT_NE(j["settings"]["statistic"].get<std::string>().find("median over repeats 2 to N"), std::string::npos);
  EXPECT_TRUE(j["settings"].contains("gbuffer_first_ms"));
  // The G-buffer's storage is made for the image size before any frame, and its time reported apart.
  EXPECT_TRUE(j["settings"].contains("gbuffer_setup_ms"));
  EXPECT_NE(r.output.find("its storage made at setup"), std::string::npos) << r.output;
  EXPECT_TRUE(j["settings"].contains("ray_scene_ms"));  // built once before any technique, in none of their times
  EXPECT_NE(r.output.find("Embree scene"), std::string::npos) << r.output;
  ASSERT_EQ(j["techniques"].size(), 2u) << j.dump(2);
  for (const auto& row : j["techniques"]) {
    ASSERT_TRUE(row["stats"].contains("first_frame_ms")) << row.dump(2);
    EXPECT_GT(row["stats"]["first_frame_ms"].get<double>(), 0.0);
    EXPECT_GT(row["total_ms"].get<double>(), 0.0);
    // Each instance's storage (both make light maps) is made before its first frame, timed apart.
    ASSERT_TRUE(row["stats"].contains("setup_ms")) << row.dump(2);
    EXPECT_GT(row["stats"]["setup_ms"].get<double>(), 0.0) << row.dump(2);
  }
  EXPECT_NE(j["settings"]["statistic"].get<std::string>().find("setup_ms"), std::string::npos);
}

}  // namespace
}  // namespace penumbra
