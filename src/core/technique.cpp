// The timing around every technique's passes: see technique.h.
#include "penumbra/technique.h"

#include "core/horizon.h"
#include "penumbra/error.h"

namespace penumbra {

void ShadowTechnique::prepare(const Scene& scene, const Light& light) {
  timings_ = {};
  preparePasses_ = 0;
  passTimer_.reset();
  horizonLight_.reset();
  prepareImpl(scene, light);
  timings_.add("prepare", passTimer_.elapsedMs());
  preparePasses_ = timings_.passes.size();
}

void ShadowTechnique::visibility(const GBuffer& gbuffer, Image<float>& v) {
  // A new visibility pass replaces the previous one's timings; the prepare's stay.
  timings_.passes.erase(timings_.passes.begin() + static_cast<std::ptrdiff_t>(preparePasses_), timings_.passes.end());
  passTimer_.reset();
  horizonInRows_ = false;
  visibilityImpl(gbuffer, v);
  if (horizonLight_ && !horizonInRows_) clampToHorizon(gbuffer, horizonBound(), v);
  timings_.add("visibility", passTimer_.elapsedMs());
}

void ShadowTechnique::reserve(int width, int height) {
  if (width < 1 || height < 1) fail("{}: reserve({}, {}): expected an image of at least 1 x 1", name(), width, height);
  reserveImpl(width, height);
}

void ShadowTechnique::endPass(std::string name) {
  timings_.add(std::move(name), passTimer_.elapsedMs());
  passTimer_.reset();
}

}  // namespace penumbra
