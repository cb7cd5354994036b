// Motion: a sequence of frames in which one light or the camera moves along a path, so that the
// techniques can be measured as real-time renderers run them, frame after frame (flicker and pops:
// penumbra/temporal_metrics.h).
//
// The path is a polyline of key points (two keys: a segment), walked at constant speed by arc length:
// frame k of N lies k / (N - 1) of the way along it, so the first frame is the first key and the last
// frame the last key. What a key means depends on what moves:
//  - a light with a position (sphere, disk, rect, polygon, segment): the light's centre sample; the
//    whole light is translated there, keeping its shape, orientation and intensity;
//  - a directional light: the direction towards the light (normalized; the keys are walked as points,
//    then normalized, so a short path turns the direction slowly);
//  - the camera: its position; it keeps looking at its look_at point.
// Nothing else changes between frames (objects, the other lights, the image size).
#pragma once

#include <string>
#include <vector>

#include "penumbra/math.h"

namespace penumbra {

struct Scene;
class Light;

enum class MotionTarget { Light, Camera };

struct Motion {
  MotionTarget target = MotionTarget::Light;
  int lightIndex = 0;      //!< the scene's light that moves (target Light), in [0, lights)
  std::vector<Vec3> path;  //!< key points, at least 2, finite; world units (a direction for a directional light)
  int frames = 12;         //!< frames in the sequence, in [2, kMaxMotionFrames]

  // Throws Error "<where>: ..." naming the field that is wrong (path too short, non-finite key, a
  // path of zero length, frames out of range, a light index the scene lacks, a directional light's
  // key at the origin, a frame whose camera is not valid).
  void validate(const Scene& scene, const std::string& where) const;

  // The key point of frame `frame` (in [0, frames)): piecewise linear along the path by arc length.
  Vec3 pointAt(int frame) const;
};

inline constexpr int kMaxMotionFrames = 1000;

// The scene at one frame of a motion: a copy of `scene` with the light or the camera moved, and no
// motion of its own (a frame is a still scene). The motion must have been validated against the scene.
Scene sceneAtFrame(const Scene& scene, const Motion& motion, int frame);

// The light moved so that its centre sample is at `center` (or, for a directional light, so that its
// direction is normalize(center)); shape, orientation, profile and intensity kept.
Light lightMovedTo(const Light& light, const Vec3& center);

}  // namespace penumbra
