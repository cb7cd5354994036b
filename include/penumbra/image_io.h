// Image files: shaded images as 8-bit sRGB PNG, visibility buffers as single-channel float EXR.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "penumbra/image.h"
#include "penumbra/math.h"

namespace penumbra {

// Linear RGB in [0, 1] (clamped) -> sRGB-encoded 8-bit PNG.
void writePng(const std::string& path, const Image<Vec3>& linearRgb);
// Single channel, 8-bit, values in [0, 1] written linearly (for visibility previews and masks).
void writePngGray(const std::string& path, const Image<float>& values);
// The 8-bit pixels those PNGs hold, in memory (row-major, no padding): sRGB-encoded RGB triples of a
// linear image, and linear gray values in [0, 1] (clamped). A live view sends these as they are.
std::vector<uint8_t> srgbBytes(const Image<Vec3>& linearRgb);
std::vector<uint8_t> grayBytes(const Image<float>& values);
// Those bytes (channels 1 or 3, width * height * channels of them) encoded as a PNG file in memory.
// Throws Error for an empty image or a size mismatch.
std::vector<uint8_t> encodePng(int width, int height, int channels, const std::vector<uint8_t>& bytes);

// Text attributes of an EXR header (name, value), e.g. the reference cache's key and checksum.
using ExrAttributes = std::vector<std::pair<std::string, std::string>>;

// Single-channel 32-bit float EXR, channel "V", with optional text attributes in its header.
void writeExr(const std::string& path, const Image<float>& values, const ExrAttributes& attributes = {});
Image<float> readExr(const std::string& path);
// Also returns the header's text attributes (OpenEXR's own and the writer's).
Image<float> readExr(const std::string& path, ExrAttributes* attributes);

// Every file above is written beside its target and renamed into place, so a file is the old one or the whole new one.

}  // namespace penumbra
