// The visibility-to-illumination table (Lawlor 2006, Appendix A): see src/core/light_profile.h.
#include "core/light_profile.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

namespace {

constexpr double kPiD = 3.14159265358979323846;

// The unit disk's part x > t, as an area (uniform) and as its limb-darkened integral.
double segmentArea(double t) { return std::acos(t) - t * std::sqrt(std::max(0.0, 1.0 - t * t)); }
double limbDarkenedSegment(double t, double u) {
  return (1.0 - u) * segmentArea(t) + u * kPiD / 2.0 * (2.0 / 3.0 - t + t * t * t / 3.0);
}

}  // namespace

std::string_view toString(VisibilityProfile profile) {
  switch (profile) {
    case VisibilityProfile::Linear:
      return "linear";
    case VisibilityProfile::UniformDisk:
      return "uniform disk";
    case VisibilityProfile::LimbDarkenedDisk:
      return "limb-darkened disk";
  }
  return "unknown";
}

double uniformDiskIllumination(double l) {
  const double t = 2.0 * std::clamp(l, 0.0, 1.0) - 1.0;  // the blocked part is x > t
  return 1.0 - segmentArea(t) / kPiD;
}

double limbDarkenedDiskIllumination(double l, double u) {
  const double t = 2.0 * std::clamp(l, 0.0, 1.0) - 1.0;
  return 1.0 - limbDarkenedSegment(t, u) / (kPiD * (1.0 - u / 3.0));
}

VisibilityToIllumination::VisibilityToIllumination(VisibilityProfile profile) : profile_(profile) {
  for (int i = 0; i <= kTableEntries; ++i) {
    const double l = static_cast<double>(i) / kTableEntries;
    double f = l;
    if (profile == VisibilityProfile::UniformDisk) f = uniformDiskIllumination(l);
    if (profile == VisibilityProfile::LimbDarkenedDisk) f = limbDarkenedDiskIllumination(l);
    table_[static_cast<size_t>(i)] = static_cast<float>(f);
  }
  table_.front() = 0.0f;  // exact ends: an umbra stays 0 and a lit point 1 after the lookup
  table_.back() = 1.0f;
}

VisibilityToIllumination VisibilityToIllumination::forLight(const Light& light) {
  switch (light.shape()) {
    case LightShape::Sphere:
    case LightShape::Disk:
      return VisibilityToIllumination(VisibilityProfile::UniformDisk);
    case LightShape::Directional:
      return VisibilityToIllumination(light.profile() == LightProfile::LimbDarkened
                                          ? VisibilityProfile::LimbDarkenedDisk
                                          : VisibilityProfile::UniformDisk);
    case LightShape::Rect:
    case LightShape::Polygon:
    case LightShape::Segment:
      return VisibilityToIllumination(VisibilityProfile::Linear);
  }
  return VisibilityToIllumination(VisibilityProfile::Linear);
}

}  // namespace penumbra
