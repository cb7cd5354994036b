// Image<T>: a dense 2D array of T, row-major, (0,0) at the top-left pixel. Pixel (x, y) covers
// [x, x+1) x [y, y+1) and is sampled at its centre (x + 0.5, y + 0.5).
#pragma once

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace penumbra {

// std::allocator, but elements made without a value are default-initialized (for arithmetic types
// and glm's vectors: left as the memory holds them) rather than zeroed. A fresh image sized by
// Image::resizeForOverwrite is then first touched by the pass that writes its pixels, on every thread
// that pass runs on, instead of by a zero fill on the calling thread (page faults dominate a first
// frame on a virtual machine).
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

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
  // held is kept where the storage is large enough, so no pass fills it first; new pixels are left
  // unset (DefaultInitAllocator).
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
  std::vector<T, DefaultInitAllocator<T>> data_;
};

}  // namespace penumbra
