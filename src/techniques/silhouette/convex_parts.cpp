// One instance of a convex-light technique per convex piece of the light, visibilities combined by
// area. See convex_parts.h.
#include "techniques/silhouette/convex_parts.h"

#include <algorithm>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "penumbra/error.h"

namespace penumbra {
namespace {

class ConvexPartsTechnique final : public ShadowTechnique {
 public:
  ConvexPartsTechnique(std::string name, std::function<std::unique_ptr<ShadowTechnique>()> make)
      : name_(std::move(name)), make_(std::move(make)) {}

  std::string_view name() const override { return name_; }

  // The instances' passes, added up by name (each instance times its own).
  PassTimings timings() const override {
    if (prepared_ <= 1) return instances_.empty() ? PassTimings{} : instances_[0]->timings();
    PassTimings sum;
    for (size_t k = 0; k < prepared_; ++k)
      for (const auto& entry : instances_[k]->timings().passes) {
        // A named element, not a structured binding: lambdas capture bindings only from C++20 compilers
        // newer than Debian's clang (make fuzz).
        auto it =
            std::find_if(sum.passes.begin(), sum.passes.end(), [&](const auto& p) { return p.first == entry.first; });
        if (it == sum.passes.end())
          sum.add(entry.first, entry.second);
        else
          it->second += entry.second;
      }
    return sum;
  }

  std::vector<std::pair<std::string, double>> stats() const override {
    if (prepared_ <= 1)
      return instances_.empty() ? std::vector<std::pair<std::string, double>>{} : instances_[0]->stats();
    std::vector<std::pair<std::string, double>> sum;
    for (size_t k = 0; k < prepared_; ++k)
      for (const auto& entry : instances_[k]->stats()) {
        auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& p) { return p.first == entry.first; });
        if (it == sum.end())
          sum.push_back(entry);
        else
          it->second += entry.second;
      }
    sum.emplace_back("light_parts", static_cast<double>(prepared_));
    return sum;
  }

 private:
  void prepareImpl(const Scene& scene, const Light& light) override {
    prepared_ = 0;
    std::vector<Light> lights;
    weights_.clear();
    const bool split = (light.shape() == LightShape::Polygon || light.shape() == LightShape::Rect) && !light.convex();
    if (split) {
      double total = 0.0;
      for (const std::vector<Vec3>& part : light.convexParts()) {
        Light piece = Light::polygon(part);
        piece.setIntensity(light.intensity());
        weights_.push_back(piece.area());
        total += piece.area();
        lights.push_back(std::move(piece));
      }
      for (double& w : weights_) w /= total;
    } else {
      lights.push_back(light);
      weights_.push_back(1.0);
    }
    while (instances_.size() < lights.size()) instances_.push_back(make_());
    const size_t count = lights.size();
    for (size_t k = 0; k < count; ++k) {
      instances_[k]->setProgressCallback(
          [this, k, count](double f) { reportProgress((static_cast<double>(k) + f) / count); });
      instances_[k]->prepare(scene, lights[k]);
    }
    prepared_ = count;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (prepared_ == 0) fail("{}: visibility() called before prepare(); call prepare(scene, light) first", name_);
    if (prepared_ == 1) {
      instances_[0]->visibility(gbuffer, v);
      return;
    }
    parts_.resize(prepared_);
    for (size_t k = 0; k < prepared_; ++k) instances_[k]->visibility(gbuffer, parts_[k]);
    const int width = gbuffer.width(), height = gbuffer.height();
    resetInParallel(v, width, height, 1.0f);
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
      for (int y = range.begin(); y < range.end(); ++y)
        for (int x = 0; x < width; ++x) {
          // The hidden fraction, summed in double; all pieces lit (hidden) gives exactly 1 (0).
          double hidden = 0.0;
          bool allHidden = true;
          for (size_t k = 0; k < prepared_; ++k) {
            const float vk = parts_[k](x, y);
            hidden += weights_[k] * (1.0 - static_cast<double>(vk));
            allHidden = allHidden && vk == 0.0f;
          }
          v(x, y) = allHidden ? 0.0f : static_cast<float>(std::clamp(1.0 - hidden, 0.0, 1.0));
        }
    });
  }

  std::string name_;
  std::function<std::unique_ptr<ShadowTechnique>()> make_;
  std::vector<std::unique_ptr<ShadowTechnique>> instances_;  //!< kept across prepares (their storage is reused)
  std::vector<double> weights_;                              //!< A_i / sum A
  std::vector<Image<float>> parts_;                          //!< V_i
  size_t prepared_ = 0;                                      //!< pieces of the last prepare (0: none)
};

}  // namespace

std::unique_ptr<ShadowTechnique> overConvexParts(std::string name,
                                                 std::function<std::unique_ptr<ShadowTechnique>()> make) {
  return std::make_unique<ConvexPartsTechnique>(std::move(name), std::move(make));
}

}  // namespace penumbra
