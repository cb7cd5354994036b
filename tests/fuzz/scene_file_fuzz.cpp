// libFuzzer target: arbitrary bytes as a scene file (src/io/scene_file.cpp). See fuzz_inputs.h for
// the contract; seeds are in tests/fuzz/corpus/scene_file/, `make fuzz` runs it.
#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  penumbra::fuzz::sceneFile(data, size);
  return 0;
}
