// The reference cache of `penumbra compare`: the truth's V (float EXR) and its stats and timings
// (JSON), stored under a key that hashes everything the truth depends on: the scene (its
// sceneToJson text, which holds the camera, the lights and every triangle), the light index, the
// image size, the reference's resolved parameters (spp, seed) and the penumbra version. A second
// compare with the same key reads the files instead of tracing the rays again.
//
// The key is 64-bit FNV-1a; the metadata repeats the key's readable parts and the scene's hash so
// that a file from another setup is never taken for this one. The EXR itself carries the key's hash
// and a checksum of its pixels in its header, so an image copied or edited over the entry (another
// technique's V, say) is caught and rendered anew, saying why. A cache entry that cannot be read
// (truncated, edited) is reported and rendered anew, not trusted. Each file is written beside its
// target and renamed into place (src/core/output_file.h), the image first, so an interrupted run
// leaves no half-written entry.
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/scene_io.h"

namespace penumbra::cli {

namespace fs = std::filesystem;

namespace {

uint64_t fnv1a(std::string_view text, uint64_t hash = 14695981039346656037ull) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return hash;
}

// The key's readable parts (everything but the scene's text, which is only hashed).
nlohmann::json keyJson(const Setup& setup, const Params& params, uint64_t sceneHash) {
  nlohmann::json params_json = nlohmann::json::object();
  for (const auto& [k, v] : describeParams(params)) params_json[k] = v;
  // format 2: the reference's rays are built in vector form (rt::buildShadowRays), which rounds
  // differently, so a truth cached by format 1 is not what this build would trace.
  return {{"format", 2},
          {"penumbra_version", PENUMBRA_VERSION},
          {"scene", setup.scene.name},
          {"scene_hash", fmt::format("{:016x}", sceneHash)},
          {"light", setup.lightIndex},
          {"width", setup.width},
          {"height", setup.height},
          {"params", params_json}};
}

// FNV-1a over the pixels' bytes: any edited value changes it.
std::string pixelChecksum(const Image<float>& v) {
  return fmt::format("{:016x}",
                     fnv1a(std::string_view(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float))));
}

constexpr const char* kKeyAttribute = "penumbra.cache_key";
constexpr const char* kChecksumAttribute = "penumbra.pixel_checksum";

std::string attribute(const ExrAttributes& attributes, const std::string& name) {
  for (const auto& [n, v] : attributes)
    if (n == name) return v;
  return {};
}

// Creates the cache folder (and its parents); the reason when that fails.
std::optional<std::string> createCacheDir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    return fmt::format("cannot create the reference cache directory '{}': {}", dir,
                       ec ? ec.message() : "a file of that name exists");
  return std::nullopt;
}

}  // namespace

ReferenceCache::ReferenceCache(std::string dir, const Setup& setup, const Params& params) : dir_(std::move(dir)) {
  const uint64_t sceneHash = fnv1a(sceneToJson(setup.scene));
  key_ = keyJson(setup, params, sceneHash).dump();
  const std::string stem = fmt::format("reference-{:016x}", fnv1a(key_));
  exrPath_ = (fs::path(dir_) / (stem + ".exr")).string();
  metaPath_ = (fs::path(dir_) / (stem + ".json")).string();
}

std::optional<CachedTruth> ReferenceCache::load(std::string& why) const {
  std::error_code ec;
  if (!fs::exists(metaPath_, ec) || !fs::exists(exrPath_, ec)) {
    why = "not cached yet";
    return std::nullopt;
  }
  try {
    std::ifstream in(metaPath_);
    std::stringstream text;
    text << in.rdbuf();
    const nlohmann::json meta = nlohmann::json::parse(text.str());
    if (meta.at("key").get<std::string>() != key_) {
      why = "its key differs (hash collision or an edited file)";
      return std::nullopt;
    }
    CachedTruth truth;
    ExrAttributes attributes;
    truth.v = readExr(exrPath_, &attributes);
    if (attribute(attributes, kKeyAttribute) != fmt::format("{:016x}", fnv1a(key_))) {
      why = "its image was not written for this key (replaced or copied from elsewhere)";
      return std::nullopt;
    }
    if (attribute(attributes, kChecksumAttribute) != pixelChecksum(truth.v)) {
      why = "its image does not match its checksum (edited or damaged)";
      return std::nullopt;
    }
    for (const auto& pass : meta.at("passes"))
      truth.timings.add(pass.at("pass").get<std::string>(), pass.at("ms").get<double>());
    for (const auto& [k, v] : meta.at("stats").items())
      truth.stats.emplace_back(k, v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN());
    return truth;
  } catch (const std::exception& e) {
    why = fmt::format("it cannot be read ({})", e.what());
    return std::nullopt;
  }
}

std::optional<std::string> ReferenceCache::whyUnwritable() const {
  if (std::optional<std::string> why = createCacheDir(dir_)) return why;
  std::string probe = (fs::path(dir_) / ".write-probe-XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) return fmt::format("cannot write in the reference cache directory '{}': {}", dir_, std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
  return std::nullopt;
}

void ReferenceCache::store(const Image<float>& v, const PassTimings& timings,
                           const std::vector<std::pair<std::string, double>>& stats) const {
  if (std::optional<std::string> why = createCacheDir(dir_))
    fail("{} (choose another with --cache-dir, or --no-cache)", *why);
  nlohmann::json meta;
  meta["key"] = key_;
  nlohmann::json passes = nlohmann::json::array();
  for (const auto& [pass, ms] : timings.passes) passes.push_back({{"pass", pass}, {"ms", ms}});
  meta["passes"] = passes;
  nlohmann::json statsJson = nlohmann::json::object();
  for (const auto& [k, x] : stats) statsJson[k] = std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
  meta["stats"] = statsJson;
  writeExr(exrPath_, v, {{kKeyAttribute, fmt::format("{:016x}", fnv1a(key_))}, {kChecksumAttribute, pixelChecksum(v)}});
  writeTextFile(metaPath_, meta.dump(2) + "\n");
}

}  // namespace penumbra::cli
