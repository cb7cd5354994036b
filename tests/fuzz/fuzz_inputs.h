// The fuzzed entry points, shared by the libFuzzer targets (tests/fuzz/*_fuzz.cpp, `make fuzz`) and by
// the test that replays the committed corpus (tests/io/fuzz_corpus_test.cpp) in the normal suite, so
// every input the fuzzer ever kept — crashes it found included — stays a regression test.
//
// The contract under test: any bytes given as a scene file or a mesh file end in a Scene or in one
// penumbra::Error. Any other exception escapes (libFuzzer reports it as a crash, the replay test as
// a failure); a crash, a sanitizer finding or a hang is found by the fuzzer itself.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "penumbra/error.h"
#include "penumbra/scene_io.h"

namespace penumbra::fuzz {

// A scene file's bytes through parseScene. A scene that loads must also survive the round trip
// through sceneToJson: written and read back, it writes the same text again.
inline void sceneFile(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Scene scene;
  try {
    // Relative mesh paths resolve in a folder that does not exist: the parser's own handling of a
    // missing mesh is under test here, mesh files are the other target's.
    scene = parseScene(text, "fuzz.json", "/nonexistent/penumbra-fuzz");
  } catch (const Error&) {
    return;
  }
  const std::string written = sceneToJson(scene);
  const Scene again = parseScene(written, "written.json");  // an Error here escapes: a round-trip bug
  if (sceneToJson(again) != written)
    throw std::logic_error("sceneToJson(parseScene(sceneToJson(s))) differs from sceneToJson(s)");
}

// The mesh-file extensions a fuzz input can choose with its first byte: the formats assimp reads that
// users are likeliest to hand penumbra.
inline constexpr std::string_view kMeshExtensions[] = {"obj", "ply", "stl", "off", "gltf",
                                                       "glb", "dae", "3ds", "fbx", "x"};

// A mesh file through the path a user's file takes: a scene file that names it in "mesh", loaded by
// parseScene, which calls importMesh. The first byte picks the file's extension (so assimp picks
// the importer by it), the rest is the file. `dir` is a scratch folder of the caller's.
inline void meshFile(const uint8_t* data, size_t size, const std::filesystem::path& dir) {
  if (size == 0) return;
  const std::string_view extension = kMeshExtensions[data[0] % std::size(kMeshExtensions)];
  const std::string name = "mesh." + std::string(extension);
  {
    std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    if (!out) throw std::runtime_error("cannot write the fuzz input to " + (dir / name).string());
  }
  const std::string scene = R"({"camera": {"position": [0, 2, 5], "look_at": [0, 0, 0]}, "lights": [],
    "objects": [{"name": "fuzzed", "mesh": ")" +
                            name + R"("}]})";
  try {
    parseScene(scene, (dir / "scene.json").string(), dir.string());
  } catch (const Error&) {
  }
}

}  // namespace penumbra::fuzz
