// The one interface every soft-shadow technique implements (docs/architecture.md, "Techniques").
// prepare() does the light-space work for one light (shadow maps, BVHs, ...); visibility() writes
// V in [0, 1] for every camera pixel of the G-buffer (1 where the pixel sees nothing).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/scene.h"
#include "penumbra/timer.h"

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

// How a light-map technique bounds V by the receiver's own surface (LightMapOptions::horizon). A map
// seen from the light's centre cannot see it: next to a smooth model's terminator, facets turned from
// the light's centre (while their shading normals still face it) are lit through the map.
enum class HorizonClamp {
  Off,     //!< the paper's V
  Facing,  //!< V = 0 where the receiver's face turns from the light's centre: its own solid hides the light
  Plane,   //!< V at most the share of the light above the plane of the receiver's face (core/horizon.h)
};

// The clamp a pass applies: its mode, and the light as the technique's map sees it (null when Off).
struct HorizonBound {
  HorizonClamp mode = HorizonClamp::Off;
  const Light* light = nullptr;
  explicit operator bool() const { return light != nullptr; }
};

// Called with the fraction done in [0, 1] by long passes; may be empty. It may be called from any
// worker thread, so it must be thread-safe; a technique calls it at most a few hundred times a pass.
using ProgressCallback = std::function<void(double)>;

// A technique derives from ShadowTechnique and implements prepareImpl() and visibilityImpl(); the
// base class's prepare() and visibility() call them and time them, so no technique carries its
// own timing code. A technique with finer passes inside one of them marks their ends with endPass().
class ShadowTechnique {
 public:
  virtual ~ShadowTechnique() = default;
  virtual std::string_view name() const = 0;
  // Throws Error naming the supported shapes if the technique does not support this light.
  void prepare(const Scene& scene, const Light& light);
  // v is resized to the G-buffer's size by the technique.
  void visibility(const GBuffer& gbuffer, Image<float>& v);
  // Makes the storage that frames of a width x height image reuse (its light maps at its map size,
  // its per-pixel buffers) and touches its pages, as an engine makes its render targets when its
  // window is sized, so that the first frame faults in no fresh memory for them. Optional: a frame
  // makes whatever is missing and remakes what another size needs; V does not depend on it. The
  // caller times it apart (penumbra bench's setup_ms).
  void reserve(int width, int height);
  // The passes of the last prepare() followed by those of the last visibility(): each call's finer
  // passes (endPass) and then its own, "prepare" or "visibility", which is the rest of the call.
  // Virtual only for a technique run as several instances of another (convex_parts.h), which adds
  // up theirs.
  virtual PassTimings timings() const { return timings_; }
  // Extra numbers a technique measures about its last run, for reports: ("rays", 6.7e7),
  // ("mean_std_error", 0.004), ... Empty by default.
  virtual std::vector<std::pair<std::string, double>> stats() const { return {}; }

  void setProgressCallback(ProgressCallback callback) { progress_ = std::move(callback); }

 protected:
  void reportProgress(double fraction) const {
    if (progress_) progress_(fraction);
  }
  // Ends a finer pass of the running prepare() or visibility(): `name` takes the time since the
  // call began or since the previous endPass() of the call.
  void endPass(std::string name);
  // Called by prepareImpl with the technique's LightMapOptions::horizon: visibility() then clamps V
  // by each receiver's own surface as `mode` says (src/core/horizon.h) after visibilityImpl, within
  // the visibility pass's time. A light-map technique passes the light as its map sees it
  // (lightAtMapOrigin), so that under a stable fit the clamp holds still with the map.
  void setHorizonClamp(HorizonClamp mode, const Light& light) {
    horizonMode_ = mode;
    if (mode != HorizonClamp::Off) horizonLight_ = light;
  }
  // For a visibilityImpl that writes V a row at a time: the clamp of this pass (empty where it is
  // off), for it to clamp each row it writes while the row's G-buffer reads are in cache
  // (clampRowToHorizon, src/core/horizon.h); visibility() then does not clamp again.
  HorizonBound horizonForRows() {
    horizonInRows_ = horizonLight_.has_value();
    return horizonBound();
  }

 private:
  virtual void prepareImpl(const Scene& scene, const Light& light) = 0;
  HorizonBound horizonBound() const {
    return horizonLight_ ? HorizonBound{horizonMode_, &*horizonLight_} : HorizonBound{};
  }
  virtual void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) = 0;
  // A technique whose frames need more than a few MiB of storage makes it here; none by default.
  virtual void reserveImpl(int width, int height) {}

  ProgressCallback progress_;
  PassTimings timings_;
  size_t preparePasses_ = 0;           //!< timings_'s passes that belong to the last prepare()
  std::optional<Light> horizonLight_;  //!< set by the last prepare() where V is clamped by the receiver
  HorizonClamp horizonMode_ = HorizonClamp::Off;
  bool horizonInRows_ = false;  //!< the running visibilityImpl clamps its rows itself
  Timer passTimer_;             //!< since the running call began or its last endPass()
};

}  // namespace penumbra
