// Replays the committed corpus of the technique-parameter fuzz target (tests/fuzz/corpus/
// technique_params/: seeds and every input the fuzzer kept or crashed on) through the entry point the
// libFuzzer target calls (tests/fuzz/technique_params_inputs.h): each input must end in V in [0, 1]
// or in a penumbra::Error, nothing else. The seeds whose outcome is known by construction are also
// checked for it, so the replay would notice an entry point that refuses everything.
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fuzz/corpus_files.h"
#include "fuzz/technique_params_inputs.h"

namespace penumbra {
namespace {

using fuzz::readBytes;
const std::filesystem::path kCorpus = fuzz::kCorpusRoot / "technique_params";

TEST(TechniqueParamsCorpus, EveryInputEndsInVisibilityOrAnError) {
  const std::vector<std::filesystem::path> files = fuzz::corpusFiles("technique_params");
  ASSERT_GE(files.size(), 20u) << "the corpus lives in " << kCorpus;
  for (const auto& file : files) {
    const std::vector<uint8_t> bytes = readBytes(file);
    EXPECT_NO_THROW(fuzz::techniqueParams(bytes.data(), bytes.size())) << file;
  }
}

// The reproduction among the seeds (pcss, light_size=100, which crashed in its disk filter)
// runs to a valid V, and a seed the schema must refuse is refused, not run.
TEST(TechniqueParamsCorpus, SeedsGiveTheirKnownOutcome) {
  const auto paramsOf = [](const std::string& name) {
    const std::vector<uint8_t> bytes = readBytes(kCorpus / name);
    const TechniqueInfo& info = techniqueRegistry()[bytes[0] % techniqueRegistry().size()];
    ParamSet given;
    std::string text(bytes.begin() + 2, bytes.end()), line;
    std::istringstream lines(text);
    while (std::getline(lines, line))
      if (!line.empty()) given.setFromKeyValue(line, name);
    return std::pair{info.name, resolveParams(info.name, info.params, given)};
  };
  const auto [pcss, params] = paramsOf("pcss_light_size_100_sphere");
  EXPECT_EQ(pcss, "pcss");
  EXPECT_EQ(params.getFloat("light_size"), 100.0);
  for (const char* refused : {"unknown_name", "bad_values", "overflowing_value", "no_equals_sign"})
    EXPECT_THROW(paramsOf(refused), Error) << refused;
}

}  // namespace
}  // namespace penumbra
