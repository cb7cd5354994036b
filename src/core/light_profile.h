// The visibility-to-illumination table of Lawlor 2006 ("Interpolation-friendly soft shadow maps",
// CGVR, Appendix A and Fig. 12; docs/papers.md).
//
// Several single-sample techniques (plm, smoothies, kirsch) compute l, the fraction of the light's
// *diameter* left visible by a straight occluder edge (Lawlor's Equation 1). V (docs/architecture.md) is the
// fraction of the emitting *area*, weighted by the light's radiance profile. For a light whose
// radiance depends on the radius alone, V is a fixed function f(l) of l along a straight edge, which
// the table stores: V = f(l), odd-symmetric about (1/2, 1/2), f(l) = 1 - f(1 - l).
//
// Profiles (l in [0, 1]; the unit disk is blocked for x > t = 2 l - 1, visible for x < t):
//  - uniform disk: f(l) = 1 - (acos t - t sqrt(1 - t^2)) / pi, the circular-segment area;
//  - limb-darkened disk, the linear law I(mu) / I(1) = 1 - u (1 - mu), mu = sqrt(1 - rho^2),
//    u = kLimbDarkeningU = 0.6 (the Sun near 550 nm; light.h, the reference samples the same law):
//    f(l) = 1 - [(1 - u)(acos t - t sqrt(1 - t^2)) + u pi / 2 (2/3 - t + t^3 / 3)] / (pi (1 - u / 3));
//  - linear: f(l) = l, exact for a segment light across the edge or a rectangle with an edge parallel
//    to it, and what a technique without a disk-shaped emitter uses.
// The paper stores a 512-entry table from an image of the Sun; we store kTableEntries + 1 samples of
// the closed forms above and interpolate linearly (error below 1e-4, tests/core/light_profile_test.cpp).
#pragma once

#include <array>
#include <string_view>

#include "penumbra/light.h"

namespace penumbra {

enum class VisibilityProfile { Linear, UniformDisk, LimbDarkenedDisk };
std::string_view toString(VisibilityProfile profile);

// Closed forms of the three profiles (see the file comment); l outside [0, 1] is clamped to it (l is
// a saturated quantity in every caller, Lawlor's Equation 2).
double uniformDiskIllumination(double l);
double limbDarkenedDiskIllumination(double l, double u = kLimbDarkeningU);

class VisibilityToIllumination {
 public:
  static constexpr int kTableEntries = 512;

  explicit VisibilityToIllumination(VisibilityProfile profile = VisibilityProfile::Linear);
  // The profile a light asks for: sphere and disk lights are uniform disks (a sphere is seen as a
  // disk; a disk light is treated as facing the receiver), a directional light is a uniform or
  // limb-darkened disk after its profile; rect, polygon and segment lights are linear.
  static VisibilityToIllumination forLight(const Light& light);

  VisibilityProfile profile() const { return profile_; }
  // f(l) by linear interpolation of the table; l is clamped to [0, 1].
  float operator()(float l) const {
    const float x = (l > 0.0f ? (l < 1.0f ? l : 1.0f) : 0.0f) * static_cast<float>(kTableEntries);
    const int i = static_cast<int>(x) < kTableEntries ? static_cast<int>(x) : kTableEntries - 1;
    const float f = x - static_cast<float>(i);
    return table_[static_cast<size_t>(i)] + f * (table_[static_cast<size_t>(i) + 1] - table_[static_cast<size_t>(i)]);
  }

 private:
  VisibilityProfile profile_;
  std::array<float, kTableEntries + 1> table_{};
};

}  // namespace penumbra
