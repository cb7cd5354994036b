// `none`: V = 1 everywhere, no shadows. Like a null graphics backend it checks the harness: shading,
// metrics and reports must run with it, and its RMSE8 against the reference is the error of
// ignoring shadows altogether.
#include <algorithm>
#include <memory>

#include "penumbra/registry.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

class NoneTechnique final : public ShadowTechnique {
 public:
  std::string_view name() const override { return "none"; }

  void prepare(const Scene&, const Light&) override {
    // Nothing to prepare, for any light shape.
    timings_ = {};
    timings_.add("prepare", 0.0);
  }

  void visibility(const GBuffer& gbuffer, Image<float>& v) override {
    Timer timer;
    v.reset(gbuffer.width(), gbuffer.height(), 1.0f);
    timings_.passes.erase(std::remove_if(timings_.passes.begin(), timings_.passes.end(),
                                         [](const auto& p) { return p.first == "visibility"; }),
                          timings_.passes.end());
    timings_.add("visibility", timer.elapsedMs());
  }

  PassTimings timings() const override { return timings_; }

 private:
  PassTimings timings_;
};

}  // namespace

TechniqueInfo noneTechniqueInfo() {
  TechniqueInfo info;
  info.name = "none";
  info.summary = "V = 1 everywhere (no shadows; checks the harness)";
  info.source = "baseline (checks the harness)";
  info.create = [](const Params&) -> std::unique_ptr<ShadowTechnique> { return std::make_unique<NoneTechnique>(); };
  return info;
}

}  // namespace penumbra
