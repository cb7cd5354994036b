// Image files: shaded images as 8-bit sRGB PNG (stb_image_write), visibility buffers as
// single-channel 32-bit float EXR (OpenEXR, channel "V", so V round-trips bit-exactly).
// sRGB encoding is the IEC 61966-2-1 piecewise curve; linear values are clamped to [0, 1] first
// (an exposure-normalized image clips only its few brightest pixels; see shade.h).
#include "penumbra/image_io.h"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include "core/output_file.h"
#include "penumbra/error.h"

namespace penumbra {

namespace {

uint8_t toByte(float unit) {
  const float c = std::isnan(unit) ? 0.0f : std::clamp(unit, 0.0f, 1.0f);
  return static_cast<uint8_t>(std::lround(c * 255.0f));
}

float srgbEncode(float linear) {
  const float c = std::isnan(linear) ? 0.0f : std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

void requireNonEmpty(const std::string& path, int width, int height) {
  if (width <= 0 || height <= 0) fail("cannot write '{}': the image is empty ({}x{})", path, width, height);
}

void writePngBytes(const std::string& path, int width, int height, int channels, const std::vector<uint8_t>& bytes) {
  replaceFile(path, [&](const std::string& temp) {
    errno = 0;
    if (!stbi_write_png(temp.c_str(), width, height, channels, bytes.data(), width * channels))
      fail("cannot write PNG '{}': {} (check that the directory exists and is writable)", path,
           errno ? std::strerror(errno) : "write failed");
  });
}

// Writes the EXR to `file` (a temporary name); messages name `path`, the file the user asked for.
void writeExrTo(const std::string& file, const std::string& path, const Image<float>& values,
                const ExrAttributes& attributes) {
  try {
    Imf::Header header(values.width(), values.height());
    header.channels().insert("V", Imf::Channel(Imf::FLOAT));
    for (const auto& [name, value] : attributes) header.insert(name, Imf::StringAttribute(value));
    Imf::OutputFile out(file.c_str(), header);
    Imf::FrameBuffer frameBuffer;
    // OpenEXR only reads through the slice; the cast drops const for its char* API.
    char* base = reinterpret_cast<char*>(const_cast<float*>(values.data()));
    frameBuffer.insert("V", Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * values.width()));
    out.setFrameBuffer(frameBuffer);
    out.writePixels(values.height());
  } catch (const std::exception& e) {
    fail("cannot write EXR '{}': {} (check that the directory exists and is writable)", path, e.what());
  }
}

}  // namespace

std::vector<uint8_t> srgbBytes(const Image<Vec3>& linearRgb) {
  std::vector<uint8_t> bytes(linearRgb.size() * 3);
  for (size_t i = 0; i < linearRgb.size(); ++i)
    for (int c = 0; c < 3; ++c) bytes[3 * i + c] = toByte(srgbEncode(linearRgb[i][c]));
  return bytes;
}

std::vector<uint8_t> grayBytes(const Image<float>& values) {
  std::vector<uint8_t> bytes(values.size());
  for (size_t i = 0; i < values.size(); ++i) bytes[i] = toByte(values[i]);
  return bytes;
}

std::vector<uint8_t> encodePng(int width, int height, int channels, const std::vector<uint8_t>& bytes) {
  if (width <= 0 || height <= 0) fail("cannot encode a PNG of an empty image ({}x{})", width, height);
  if ((channels != 1 && channels != 3) ||
      bytes.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * static_cast<size_t>(channels))
    fail("cannot encode a PNG: {} bytes for {}x{} pixels of {} channel(s)", bytes.size(), width, height, channels);
  std::vector<uint8_t> png;
  const auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    const auto* first = static_cast<const uint8_t*>(data);
    out->insert(out->end(), first, first + size);
  };
  if (!stbi_write_png_to_func(append, &png, width, height, channels, bytes.data(), width * channels))
    fail("cannot encode a PNG of {}x{} pixels", width, height);
  return png;
}

void writePng(const std::string& path, const Image<Vec3>& linearRgb) {
  requireNonEmpty(path, linearRgb.width(), linearRgb.height());
  writePngBytes(path, linearRgb.width(), linearRgb.height(), 3, srgbBytes(linearRgb));
}

void writePngGray(const std::string& path, const Image<float>& values) {
  requireNonEmpty(path, values.width(), values.height());
  writePngBytes(path, values.width(), values.height(), 1, grayBytes(values));
}

void writeExr(const std::string& path, const Image<float>& values, const ExrAttributes& attributes) {
  requireNonEmpty(path, values.width(), values.height());
  replaceFile(path, [&](const std::string& temp) { writeExrTo(temp, path, values, attributes); });
}

Image<float> readExr(const std::string& path) { return readExr(path, nullptr); }

Image<float> readExr(const std::string& path, ExrAttributes* attributes) {
  try {
    Imf::InputFile file(path.c_str());
    if (attributes) {
      attributes->clear();
      for (auto it = file.header().begin(); it != file.header().end(); ++it)
        if (const auto* text = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
          attributes->emplace_back(it.name(), text->value());
    }
    const Imath::Box2i window = file.header().dataWindow();
    if (!file.header().channels().findChannel("V"))
      fail("cannot read EXR '{}': it has no channel \"V\" (penumbra writes visibility as channel \"V\")", path);
    const int width = window.max.x - window.min.x + 1;
    const int height = window.max.y - window.min.y + 1;
    Image<float> values(width, height, 0.0f);
    Imf::FrameBuffer frameBuffer;
    // The slice base is offset so that the data window's first pixel lands at values(0, 0).
    char* base = reinterpret_cast<char*>(values.data()) -
                 (static_cast<std::ptrdiff_t>(window.min.x) + static_cast<std::ptrdiff_t>(window.min.y) * width) *
                     static_cast<std::ptrdiff_t>(sizeof(float));
    frameBuffer.insert("V", Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * width));
    file.setFrameBuffer(frameBuffer);
    file.readPixels(window.min.y, window.max.y);
    return values;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("cannot read EXR '{}': {}", path, e.what());
  }
}

}  // namespace penumbra
