// libFuzzer target: arbitrary bytes as a mesh file named by a scene file (src/io/mesh_import.cpp via
// src/io/scene_file.cpp, through assimp). See fuzz_inputs.h for the contract; seeds are in
// tests/fuzz/corpus/mesh_file/ (first byte: the format), `make fuzz` runs it. assimp itself comes from
// Debian without coverage instrumentation, so the fuzzer's guidance covers penumbra's side only.
#include <unistd.h>

#include <filesystem>

#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // One scratch folder per fuzzing process (libFuzzer's -jobs run several side by side).
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("penumbra-fuzz-mesh-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  penumbra::fuzz::meshFile(data, size, dir);
  return 0;
}
