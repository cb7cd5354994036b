// Image<T>: a dense 2D array of T, row-major, (0,0) at the top-left pixel. Pixel (x, y) covers
// [x, x+1) x [y, y+1) and is sampled at its centre (x + 0.5, y + 0.5).
#pragma once

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <vector>

namespace penumbra {

template <class T>
class Image {
 public:
  Image() = default;
  Image(int width, int height, const T& fill = T{})
      : width_(width), height_(height), data_(static_cast<size_t>(width) * height, fill) {}

  int width() const { return width_; }
  int height() const { return height_; }
  size_t size() const { return data_.size(); }
  bool empty() const { return data_.empty(); }

  T& operator()(int x, int y) {
    assert(x >= 0 && x < width_ && y >= 0 && y < height_);
    return data_[static_cast<size_t>(y) * width_ + x];
  }
  const T& operator()(int x, int y) const {
    assert(x >= 0 && x < width_ && y >= 0 && y < height_);
    return data_[static_cast<size_t>(y) * width_ + x];
  }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  T* row(int y) { return data_.data() + static_cast<size_t>(y) * width_; }
  const T* row(int y) const { return data_.data() + static_cast<size_t>(y) * width_; }

  void fill(const T& value) { std::fill(data_.begin(), data_.end(), value); }
  // Becomes a width x height image of `value`, keeping its storage where it is large enough: a
  // technique's output refilled every frame costs a pass over memory, not fresh pages.
  void reset(int width, int height, const T& value) {
    width_ = width;
    height_ = height;
    data_.assign(static_cast<size_t>(width) * height, value);
  }
  // Becomes a width x height image whose pixels the caller is about to write, every one: what it
  // held is kept where the storage is large enough, so no pass fills it first.
  void resizeForOverwrite(int width, int height) {
    width_ = width;
    height_ = height;
    data_.resize(static_cast<size_t>(width) * height);
  }
  auto begin() { return data_.begin(); }
  auto end() { return data_.end(); }
  auto begin() const { return data_.begin(); }
  auto end() const { return data_.end(); }

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<T> data_;
};

}  // namespace penumbra
