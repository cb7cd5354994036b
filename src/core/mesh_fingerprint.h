// A fingerprint of a mesh's geometry, by which the techniques keep what they build from the geometry
// alone (edge adjacency, BVHs) while a light or the camera moves over a static scene.
#pragma once

#include <cstdint>

#include "penumbra/scene.h"

namespace penumbra {

// Two independent 64-bit multiply-xorshift hashes of every 64-bit word of a mesh's positions and
// triangles (and their counts): equal fingerprints stand for geometry the same to the bit.
struct MeshFingerprint {
  uint64_t a = 0, b = 0;
  bool operator==(const MeshFingerprint&) const = default;
};
MeshFingerprint meshFingerprint(const Mesh& mesh);

}  // namespace penumbra
