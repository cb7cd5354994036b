// The committed fuzz corpora (tests/fuzz/corpus/<target>/) as the replay tests read them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace penumbra::fuzz {

inline const std::filesystem::path kCorpusRoot = std::filesystem::path(PENUMBRA_SOURCE_DIR) / "tests/fuzz/corpus";

inline std::vector<uint8_t> readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Every file of target's corpus, sorted by name.
inline std::vector<std::filesystem::path> corpusFiles(const std::string& target) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(kCorpusRoot / target))
    if (entry.is_regular_file()) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace penumbra::fuzz
