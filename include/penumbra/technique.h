// The one interface every soft-shadow technique implements (docs/architecture.md, "Techniques").
// prepare() does the light-space work for one light (shadow maps, BVHs, ...); visibility() writes
// V in [0, 1] for every camera pixel of the G-buffer (1 where the pixel sees nothing).
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/scene.h"

namespace penumbra {

// Wall-clock milliseconds per pass, in the order they ran ("prepare", "visibility", or finer).
struct PassTimings {
  std::vector<std::pair<std::string, double>> passes;
  void add(std::string name, double ms) { passes.emplace_back(std::move(name), ms); }
  double get(std::string_view name) const {
    for (const auto& [n, ms] : passes)
      if (n == name) return ms;
    return 0.0;
  }
  double total() const {
    double t = 0.0;
    for (const auto& p : passes) t += p.second;
    return t;
  }
};

// Called with the fraction done in [0, 1] by long passes; may be empty. It may be called from any
// worker thread, so it must be thread-safe; a technique calls it at most a few hundred times a pass.
using ProgressCallback = std::function<void(double)>;

class ShadowTechnique {
 public:
  virtual ~ShadowTechnique() = default;
  virtual std::string_view name() const = 0;
  // Throws Error naming the supported shapes if the technique does not support this light.
  virtual void prepare(const Scene& scene, const Light& light) = 0;
  // v is resized to the G-buffer's size by the technique.
  virtual void visibility(const GBuffer& gbuffer, Image<float>& v) = 0;
  virtual PassTimings timings() const = 0;
  // Extra numbers a technique measures about its last run, for reports: ("rays", 6.7e7),
  // ("mean_std_error", 0.004), ... Empty by default.
  virtual std::vector<std::pair<std::string, double>> stats() const { return {}; }

  void setProgressCallback(ProgressCallback callback) { progress_ = std::move(callback); }

 protected:
  void reportProgress(double fraction) const {
    if (progress_) progress_(fraction);
  }

 private:
  ProgressCallback progress_;
};

}  // namespace penumbra
