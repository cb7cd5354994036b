// Image::reset with the fill split across the worker threads: a 1024^2 image holds 4-20 MB, which
// one thread alone fills at a fraction of the memory's bandwidth (and, the first time, faults in).
#pragma once

#include <algorithm>
#include <type_traits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "penumbra/image.h"

namespace penumbra {

template <class T>
void resetInParallel(Image<T>& image, int width, int height, const std::type_identity_t<T>& value) {
  image.resizeForOverwrite(width, height);
  tbb::parallel_for(tbb::blocked_range<int>(0, height, 32), [&](const tbb::blocked_range<int>& rows) {
    std::fill(image.row(rows.begin()), image.row(rows.begin()) + static_cast<size_t>(rows.size()) * width, value);
  });
}

}  // namespace penumbra
