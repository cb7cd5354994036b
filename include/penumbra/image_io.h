// Image files: shaded images as 8-bit sRGB PNG, visibility buffers as single-channel float EXR.
#pragma once

#include <string>

#include "penumbra/image.h"
#include "penumbra/math.h"

namespace penumbra {

// Linear RGB in [0, 1] (clamped) -> sRGB-encoded 8-bit PNG.
void writePng(const std::string& path, const Image<Vec3>& linearRgb);
// Single channel, 8-bit, values in [0, 1] written linearly (for visibility previews and masks).
void writePngGray(const std::string& path, const Image<float>& values);
// Single-channel 32-bit float EXR, channel "V".
void writeExr(const std::string& path, const Image<float>& values);
Image<float> readExr(const std::string& path);

}  // namespace penumbra
