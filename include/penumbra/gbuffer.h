// The camera G-buffer (docs/architecture.md): per pixel, hit flag, world position, shading normal, object id,
// triangle id and view depth. Every technique consumes the same G-buffer, so differences in the
// output are differences of the techniques alone.
#pragma once

#include <cstdint>

#include "penumbra/image.h"
#include "penumbra/math.h"

namespace penumbra {

inline constexpr int32_t kNoObject = -1;

struct GBuffer {
  Image<Vec3> wsPosition;         //!< world-space hit position
  Image<Vec3> wsNormal;           //!< unit shading normal, facing the camera
  Image<Vec3> wsGeometricNormal;  //!< unit face normal, facing the camera
  Image<int32_t> objectId;        //!< kNoObject where the pixel sees nothing
  Image<int32_t> triangleId;      //!< index into the object's mesh triangles; -1 on a miss
  Image<float> csDepth;           //!< view depth (distance along the view axis); kInfinity on a miss

  GBuffer() = default;
  GBuffer(int width, int height)
      : wsPosition(width, height, Vec3(0.0f)),
        wsNormal(width, height, Vec3(0.0f)),
        wsGeometricNormal(width, height, Vec3(0.0f)),
        objectId(width, height, kNoObject),
        triangleId(width, height, -1),
        csDepth(width, height, kInfinity) {}

  int width() const { return objectId.width(); }
  int height() const { return objectId.height(); }
  bool hit(int x, int y) const { return objectId(x, y) != kNoObject; }
};

}  // namespace penumbra
