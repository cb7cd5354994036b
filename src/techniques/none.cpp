// `none`: V = 1 everywhere, no shadows. Like a null graphics backend it checks the harness: shading,
// metrics and reports must run with it, and its RMSE8 against the reference is the error of
// ignoring shadows altogether.
#include <memory>

#include "core/image_fill.h"
#include "penumbra/registry.h"

namespace penumbra {
namespace {

class NoneTechnique final : public ShadowTechnique {
 public:
  std::string_view name() const override { return "none"; }

 private:
  void prepareImpl(const Scene&, const Light&) override {}  // nothing to prepare, for any light shape

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    resetInParallel(v, gbuffer.width(), gbuffer.height(), 1.0f);
  }
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
