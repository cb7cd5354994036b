// Malformed input files: non-finite vertices are refused at load through the path a user's file
// takes (a scene file naming a mesh file, or inline positions), with the file and the vertex index
// named; and the invalid and odd models of Debian's assimp-testmodels package (empty files,
// out-of-range indices, a header that asks for hundreds of GB, UTF-16 and BOM-prefixed text, CR and
// CRLF line endings, a file without a final line ending) each load to a valid mesh or end in one
// penumbra::Error that names the file — never a crash or another exception.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

class ScratchDir {
 public:
  ScratchDir()
      : path_(std::filesystem::temp_directory_path() / ("penumbra-malformed-test-" + std::to_string(getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::filesystem::path write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path_ / name, std::ios::binary) << bytes;
    return path_ / name;
  }

 private:
  std::filesystem::path path_;
};

std::string loadError(const std::filesystem::path& scenePath) {
  try {
    loadScene(scenePath.string());
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const char* kSceneHead = R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0]}, "lights": [], "objects": [)";

TEST(MalformedFiles, NonFiniteMeshVerticesAreRefusedThroughTheSceneFile) {
  const ScratchDir dir;
  // The third vertex of the second object's file is not finite: NaN, +inf, and a number past float range.
  for (const std::string bad : {"nan", "inf", "-inf", "1e39"}) {
    dir.write("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    dir.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 " + bad + " 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n");
    const auto scene =
        dir.write("scene.json",
                  std::string(kSceneHead) + R"({"name": "a", "mesh": "ok.obj"}, {"name": "b", "mesh": "bad.obj"}]})");
    const std::string message = loadError(scene);
    EXPECT_FALSE(message.empty()) << bad << ": a non-finite vertex must be refused";
    EXPECT_NE(message.find(scene.string()), std::string::npos) << "names the scene file: " << message;
    EXPECT_NE(message.find("objects[1].mesh"), std::string::npos) << "names the field: " << message;
    EXPECT_NE(message.find("bad.obj"), std::string::npos) << "names the mesh file: " << message;
    EXPECT_NE(message.find("vertex 2 "), std::string::npos) << "names the vertex index: " << message;
  }
}

TEST(MalformedFiles, NonFiniteInlineVerticesAreRefusedWithTheirIndex) {
  const ScratchDir dir;
  const auto scene = dir.write("inline.json", std::string(kSceneHead) + R"({"name": "t", "inline": {
      "positions": [[0, 0, 0], [1, 0, 0], [0, 1e39, 0]], "triangles": [[0, 1, 2]]}}]})");
  const std::string message = loadError(scene);
  EXPECT_NE(message.find(scene.string()), std::string::npos) << message;
  EXPECT_NE(message.find("objects[0].inline.positions[2]"), std::string::npos) << message;
  EXPECT_NE(message.find("finite"), std::string::npos) << message;
}

TEST(MalformedFiles, TruncatedPlyHeaderIsRefusedInsteadOfHanging) {
  // assimp 5.2.5 loops forever on these (found by the mesh-file fuzz target); the importer refuses them first.
  const ScratchDir dir;
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  for (const auto& [name, bytes] :
       {std::pair<std::string, std::string>{"truncated.ply", head},
        {"no_end.ply", head + "element face 1\nxend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
        {"by_signature.mesh", head}}) {
    const auto path = dir.write(name, bytes);
    try {
      importMesh(path.string());
      ADD_FAILURE() << name << " must be refused";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("end_header"), std::string::npos) << e.what();
    }
  }
  // A complete header with CRLF line endings still loads.
  const auto crlf = dir.write("crlf.ply",
                              "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n"
                              "property float z\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
                              "end_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n");
  EXPECT_EQ(importMesh(crlf.string()).triangleCount(), 1u);
}

TEST(MalformedFiles, ElementCountsBeyondTheFileSizeAreRefused) {
  // assimp reserves what the header declares before reading: these would ask for hundreds of GB.
  const ScratchDir dir;
  for (const auto& [name, bytes] : {std::pair<std::string, std::string>{"huge.off", "OFF\n35353523535 6 0\n0 0 0\n"},
                                    {"huge_same_line.off", "OFF 3 99999999999\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
                                    {"huge.ply",
                                     "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
                                     "property float y\nproperty float z\nend_header\n0 0 0\n"}}) {
    const auto path = dir.write(name, bytes);
    try {
      importMesh(path.string());
      ADD_FAILURE() << name << " must be refused";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("declares"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(importMesh(dir.write("ok.off", "OFF\n# a comment\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").string())
                .triangleCount(),
            1u);
}

const std::filesystem::path kTestModels = "/usr/share/assimp/models";

// The odd files of assimp-testmodels (outside invalid/) and the outcome measured for each with
// assimp 5.2.5: true = loads to a mesh, false = an Error naming the file. assimp 5.2.5 reads UTF-8
// with a byte-order mark but none of the UTF-16 files: they end in "cannot import" or "incomplete".
struct OddModel {
  const char* path;
  const char* what;
  bool loads;
};
const OddModel kOddModels[] = {
    {"OBJ/box_UTF16BE.obj", "UTF-16 big-endian text, CRLF", false},
    {"OBJ/box_without_lineending.obj", "no line ending after the last line", true},
    {"OBJ/cube_mtllib_after_g.obj", "CRLF line endings", true},
    {"OBJ/empty_mat.obj", "an empty material", true},
    {"OBJ/number_formats.obj", "numbers in unusual notations", true},
    {"OBJ/point_cloud.obj", "points only, no surface", false},
    {"OBJ/testline.obj", "lines only, no surface", false},
    {"OFF/invalid.off", "CR and LF line endings mixed, fewer face lines than declared", false},
    {"AC/SphereWithLight_UTF16LE.ac", "UTF-16 little-endian text", false},
    {"AC/SphereWithLight_UTF8BOM.ac", "UTF-8 with a byte-order mark", true},
    {"ASE/ThreeCubesGreen_UTF16BE.ASE", "UTF-16 big-endian text", false},
    {"ASE/ThreeCubesGreen_UTF16LE.ASE", "UTF-16 little-endian text", false},
    {"Collada/cube_UTF16LE.dae", "UTF-16 little-endian XML", false},
    {"Collada/cube_UTF8BOM.dae", "UTF-8 XML with a byte-order mark", true},
    {"Collada/cube_emptyTags.dae", "empty XML tags", true},
    {"STL/triangle_with_empty_solid.stl", "an empty solid next to a triangle", true},
};

void requireTestModels() {
  ASSERT_TRUE(std::filesystem::is_directory(kTestModels / "invalid"))
      << kTestModels << " is missing: install Debian's test models with `sudo apt-get install assimp-testmodels` "
      << "(scripts/install-deps installs it)";
}

// Imports `path`; returns "" when it loads to a valid mesh, else the Error's message. Fails the test
// on any other exception or on a mesh that is not valid.
std::string importOutcome(const std::filesystem::path& path) {
  try {
    const Mesh mesh = importMesh(path.string());
    EXPECT_GT(mesh.triangleCount(), 0u) << path;
    size_t bad = 0;
    for (const Vec3& p : mesh.positions) bad += !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    for (const glm::uvec3& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) bad += t[k] >= mesh.positions.size();
    EXPECT_EQ(bad, 0u) << path << ": non-finite positions or indices out of range";
    EXPECT_TRUE(mesh.normals.empty() || mesh.normals.size() == mesh.positions.size()) << path;
    return "";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << "the message names the file: " << message;
    return message.empty() ? "(empty message)" : message;
  }
}

TEST(MalformedFiles, AssimpInvalidModelsAreRefusedNamingTheFile) {
  requireTestModels();
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kTestModels / "invalid")) {
    const auto& path = entry.path();
    if (path.filename() == "readme.txt") continue;
    ++files;
    const std::string outcome = importOutcome(path);
    // malformed2.obj only names a missing material: its triangles are fine and load.
    if (path.filename() == "malformed2.obj")
      EXPECT_EQ(outcome, "") << path;
    else
      EXPECT_NE(outcome, "") << path << " is invalid and must be refused";
  }
  EXPECT_GE(files, 14u) << "assimp-testmodels' invalid/ holds 15 models";
}

TEST(MalformedFiles, AssimpOddModelsLoadOrAreRefusedNamingTheFile) {
  requireTestModels();
  for (const OddModel& model : kOddModels) {
    const std::string outcome = importOutcome(kTestModels / model.path);
    EXPECT_EQ(outcome.empty(), model.loads) << model.path << " (" << model.what << "): " << outcome;
  }
}

}  // namespace
}  // namespace penumbra
