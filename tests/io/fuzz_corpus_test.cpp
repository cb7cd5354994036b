// Replays the committed fuzz corpus (tests/fuzz/corpus/<target>/, seeds and every input the fuzzer
// kept or crashed on) through the same entry points the libFuzzer targets call (tests/fuzz/
// fuzz_inputs.h): each input must end in a scene or a penumbra::Error — nothing else may escape.
// The seeds whose outcome is known by construction are also checked for that outcome, so the
// replay would notice a parser that refuses everything.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fuzz/corpus_files.h"
#include "fuzz/fuzz_inputs.h"
#include "penumbra/error.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

using fuzz::corpusFiles;
using fuzz::readBytes;
const std::filesystem::path kCorpus = fuzz::kCorpusRoot;

class ScratchDir {
 public:
  ScratchDir() : path_(std::filesystem::temp_directory_path() / ("penumbra-corpus-test-" + std::to_string(getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

TEST(FuzzCorpus, EverySceneInputEndsInASceneOrAnError) {
  const auto files = corpusFiles("scene_file");
  ASSERT_GE(files.size(), 10u) << "the scene corpus lives in " << (kCorpus / "scene_file");
  for (const auto& file : files) {
    const std::vector<uint8_t> bytes = readBytes(file);
    EXPECT_NO_THROW(fuzz::sceneFile(bytes.data(), bytes.size())) << file;
  }
}

TEST(FuzzCorpus, SceneSeedsGiveTheirKnownOutcome) {
  const auto parse = [](const std::string& name) {
    const std::vector<uint8_t> bytes = readBytes(kCorpus / "scene_file" / name);
    return parseScene(std::string(bytes.begin(), bytes.end()), name, "/nonexistent/penumbra-fuzz");
  };
  for (const char* good : {"torus.json", "triangle.json", "slit.json", "inline_lights.json", "primitives.json"})
    EXPECT_NO_THROW(parse(good)) << good;
  EXPECT_EQ(parse("inline_lights.json").lights.size(), 6u);
  for (const char* bad :
       {"malformed_truncated.json", "duplicate_key.json", "huge_number.json", "bad_indices.json", "mesh_missing.json",
        "big_image.json", "not_object.json", "empty.json", "utf16.json", "crash-json-number-overflow"}) {
    try {
      parse(bad);
      ADD_FAILURE() << bad << " must be refused";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(bad, 0), 0u) << "the message starts with the file: " << e.what();
    }
  }
  // A fuzz finding: a number too large for a double ended the process through an uncaught
  // exception of the JSON reader; it is now an Error naming where the number is.
  try {
    parse("crash-json-number-overflow");
    ADD_FAILURE() << "an overflowing number must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("inline.triangles[0][2]: number overflow"), std::string::npos) << e.what();
  }
}

TEST(FuzzCorpus, EveryMeshInputEndsInASceneOrAnError) {
  const auto files = corpusFiles("mesh_file");
  ASSERT_GE(files.size(), 8u) << "the mesh corpus lives in " << (kCorpus / "mesh_file");
  const ScratchDir dir;
  for (const auto& file : files) {
    const std::vector<uint8_t> bytes = readBytes(file);
    EXPECT_NO_THROW(fuzz::meshFile(bytes.data(), bytes.size(), dir.path())) << file;
  }
}

TEST(FuzzCorpus, MeshSeedsGiveTheirKnownOutcome) {
  // The seeds' first byte picks the extension (fuzz_inputs.h); write them as the fuzz target does.
  const ScratchDir dir;
  const auto import = [&](const std::string& name) {
    const std::vector<uint8_t> bytes = readBytes(kCorpus / "mesh_file" / name);
    const auto path = dir.path() / (std::filesystem::path(name).stem().string() + "." +
                                    std::string(fuzz::kMeshExtensions[bytes.at(0) % std::size(fuzz::kMeshExtensions)]));
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data() + 1), static_cast<std::streamsize>(bytes.size() - 1));
    return importMesh(path.string());
  };
  EXPECT_EQ(import("tetra.obj").triangleCount(), 4u);
  EXPECT_EQ(import("quad_crlf.obj").triangleCount(), 2u);
  EXPECT_EQ(import("tri.ply").triangleCount(), 1u);
  EXPECT_EQ(import("tri.stl").triangleCount(), 1u);
  EXPECT_EQ(import("quad.off").triangleCount(), 2u);
  EXPECT_EQ(import("tri.gltf").triangleCount(), 1u);
  for (const char* bad : {"nan.obj", "lines_only.obj", "bad_index.obj"}) EXPECT_THROW(import(bad), Error) << bad;
  // A fuzz finding: a PLY whose damaged header leaves a face without indices aborted the process
  // in assimp's triangulation; faces are now checked first.
  try {
    import("crash-assimp-ply-index-out-of-range");
    ADD_FAILURE() << "a face without vertices must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("has no vertices"), std::string::npos) << e.what();
  }
  // A fuzz finding: an OFF face of no vertices read out of bounds inside assimp's OFF reader.
  try {
    import("crash-assimp-off-empty-face");
    ADD_FAILURE() << "an OFF face without vertices must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("expected its vertex count, 3 or more"), std::string::npos) << e.what();
  }
  // A fuzz finding: a vertex count too long for 64 bits overflowed in assimp into a 16 GB allocation.
  try {
    import("oom-assimp-off-overflowing-count");
    ADD_FAILURE() << "an overflowing count must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("more than the file"), std::string::npos) << e.what();
  }
  // A fuzz finding: a file named .obj that opens with "ply" went to assimp's PLY reader, which read
  // past its buffer on a header without end_header; such a file is refused first.
  try {
    import("crash-assimp-ply-prefix-overread");
    ADD_FAILURE() << "a PLY-looking file without end_header must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("end_header"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra
