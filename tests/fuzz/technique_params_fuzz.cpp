// libFuzzer target: technique parameters (names and values as typed after --param) on a small scene
// under every light shape. See technique_params_inputs.h for the contract and the input layout; seeds
// are in tests/fuzz/corpus/technique_params/, `make fuzz` runs it.
#include "fuzz/technique_params_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  penumbra::fuzz::techniqueParams(data, size);
  return 0;
}
