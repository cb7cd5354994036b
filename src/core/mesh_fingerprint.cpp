// meshFingerprint (mesh_fingerprint.h). It runs in every steady prepare of the techniques that keep
// geometry caches, so it is made fast: each hash keeps four independent chains over interleaved words
// (a multiply's latency, not its throughput, bounds one chain), and a large mesh is hashed in fixed
// chunks in parallel, combined in chunk order (the value does not depend on the thread count).
#include "core/mesh_fingerprint.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace penumbra {

namespace {

constexpr uint64_t kMulA = 0xFF51AFD7ED558CCDull;
constexpr uint64_t kMulB = 0xC4CEB9FE1A85EC53ull;
constexpr size_t kChunkWords = size_t{1} << 16;  //!< 512 KiB of geometry per parallel chunk

inline uint64_t mixA(uint64_t h, uint64_t word) {
  h = (h ^ word) * kMulA;
  return h ^ (h >> 32);
}
inline uint64_t mixB(uint64_t h, uint64_t word) {
  h = (h + word) * kMulB;
  return h ^ (h >> 29);
}

inline uint64_t loadWord(const unsigned char* p) {
  uint64_t w;
  std::memcpy(&w, p, 8);
  return w;
}

// Both hashes of `bytes` bytes at p (a trailing partial word zero-padded), seeded with `seed`.
MeshFingerprint hashBytes(const unsigned char* p, size_t bytes, uint64_t seed) {
  uint64_t a[4], b[4];
  for (int lane = 0; lane < 4; ++lane) {
    a[lane] = mixA(0x9E3779B97F4A7C15ull + static_cast<uint64_t>(lane), seed);
    b[lane] = mixB(0xC2B2AE3D27D4EB4Full + static_cast<uint64_t>(lane), seed);
  }
  const size_t words = bytes / 8;
  size_t i = 0;
  for (; i + 4 <= words; i += 4)
    for (int lane = 0; lane < 4; ++lane) {
      const uint64_t w = loadWord(p + 8 * (i + static_cast<size_t>(lane)));
      a[lane] = mixA(a[lane], w);
      b[lane] = mixB(b[lane], w);
    }
  for (; i < words; ++i) {
    const uint64_t w = loadWord(p + 8 * i);
    a[0] = mixA(a[0], w);
    b[0] = mixB(b[0], w);
  }
  if (bytes % 8 != 0) {
    uint64_t w = 0;
    std::memcpy(&w, p + words * 8, bytes % 8);
    a[1] = mixA(a[1], w);
    b[1] = mixB(b[1], w);
  }
  MeshFingerprint out{bytes, bytes};
  for (int lane = 0; lane < 4; ++lane) {
    out.a = mixA(out.a, a[lane]);
    out.b = mixB(out.b, b[lane]);
  }
  return out;
}

// The hashes of a buffer: of each chunk (in parallel when there are several), combined in order.
MeshFingerprint hashBuffer(const void* data, size_t bytes, uint64_t seed) {
  const auto* p = static_cast<const unsigned char*>(data);
  const size_t chunkBytes = 8 * kChunkWords;
  const size_t chunks = (bytes + chunkBytes - 1) / chunkBytes;
  if (chunks <= 1) return hashBytes(p, bytes, seed);
  std::vector<MeshFingerprint> parts(chunks);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t c = range.begin(); c < range.end(); ++c)
      parts[c] = hashBytes(p + c * chunkBytes, std::min(chunkBytes, bytes - c * chunkBytes), seed + c);
  });
  MeshFingerprint out{seed, seed};
  for (const MeshFingerprint& part : parts) {
    out.a = mixA(out.a, part.a);
    out.b = mixB(out.b, part.b);
  }
  return out;
}

}  // namespace

MeshFingerprint meshFingerprint(const Mesh& mesh) {
  const MeshFingerprint positions = hashBuffer(mesh.positions.data(), mesh.positions.size() * sizeof(Vec3), 1);
  const MeshFingerprint triangles = hashBuffer(mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3), 2);
  MeshFingerprint key{mesh.positions.size(), mesh.triangles.size()};
  key.a = mixA(mixA(mixA(key.a, key.b), positions.a), triangles.a);
  key.b = mixB(mixB(mixB(key.b, key.a), positions.b), triangles.b);
  return key;
}

}  // namespace penumbra
