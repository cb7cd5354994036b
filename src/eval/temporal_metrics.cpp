// Temporal error of a frame sequence (include/penumbra/temporal_metrics.h).
#include "penumbra/temporal_metrics.h"

#include <cmath>

#include "penumbra/error.h"
#include "penumbra/metrics.h"

namespace penumbra {

TemporalStats temporalError(const std::vector<Image<float>>& v, const std::vector<Image<float>>& reference,
                            const std::vector<Image<uint8_t>>& masks) {
  if (v.size() < 2) fail("temporal error: {} frame(s): a sequence needs at least 2", v.size());
  if (reference.size() != v.size() || masks.size() != v.size())
    fail("temporal error: {} frames of V, {} of the reference and {} masks: expected the same count", v.size(),
         reference.size(), masks.size());
  const int width = v[0].width(), height = v[0].height();
  for (size_t k = 0; k < v.size(); ++k)
    for (const auto& [w, h] :
         {std::pair{v[k].width(), v[k].height()}, std::pair{reference[k].width(), reference[k].height()},
          std::pair{masks[k].width(), masks[k].height()}})
      if (w != width || h != height)
        fail("temporal error: frame {} has an image of {} x {}: expected {} x {} like frame 0", k, w, h, width, height);

  TemporalStats stats;
  stats.framePairs = v.size() - 1;
  double sum = 0.0;
  size_t reversed = 0, popsWithNext = 0;
  // Sign of each pixel's pop at the previous pair (0: no pop there), to find pops undone a frame later.
  std::vector<int8_t> previousPop(static_cast<size_t>(width) * static_cast<size_t>(height), 0);
  std::vector<int8_t> pop(previousPop.size(), 0);
  for (size_t k = 0; k + 1 < v.size(); ++k) {
    const bool hasNext = k + 2 < v.size();
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const size_t i = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
        pop[i] = 0;
        if (!masks[k](x, y) || !masks[k + 1](x, y)) continue;
        const float a = v[k](x, y), b = v[k + 1](x, y), ra = reference[k](x, y), rb = reference[k + 1](x, y);
        if (!(inPenumbra(a) || inPenumbra(b) || inPenumbra(ra) || inPenumbra(rb))) continue;
        const double signedError = (static_cast<double>(b) - a) - (static_cast<double>(rb) - ra);
        const double e = std::abs(signedError);
        sum += e;
        ++stats.pixels;
        if (e > kPopJump) {
          ++stats.pops;
          pop[i] = signedError > 0.0 ? 1 : -1;
          if (hasNext) ++popsWithNext;
          if (previousPop[i] == -pop[i]) ++reversed;
        }
      }
    std::swap(previousPop, pop);
  }
  stats.flicker = stats.pixels ? sum / static_cast<double>(stats.pixels) * 255.0 : 0.0;
  stats.popRate = stats.pixels ? static_cast<double>(stats.pops) / static_cast<double>(stats.pixels) : 0.0;
  stats.reversedPops = popsWithNext ? static_cast<double>(reversed) / static_cast<double>(popsWithNext) : 0.0;
  return stats;
}

}  // namespace penumbra
