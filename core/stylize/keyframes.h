#pragma once
/// \file keyframes.h
/// The stylizer's camera path (issue #15, the GI paper Sec. 4.3): key frames of camera and TF,
/// interpolated linearly between the two keys around a time, so the frame at a key is that key's
/// and the TF midway is the two keys' TFs averaged texel by texel. GL-free.

#include <cstddef>

#include "core/image/image.h"
#include "core/stylize/scene.h"

namespace volstyle::core {

/// Where `time` falls on the path: between keys `before` and `after` (equal before the first key
/// and after the last), `weight` of the way to `after`.
struct PathPosition {
    size_t before = 0, after = 0;
    double weight = 0;
};
PathPosition pathPosition(const std::vector<StylizerKeyframe>& keys, double time);

/// Eye, target, up, field of view and near/far linearly; the size is `a`'s.
Camera interpolateCamera(const Camera& a, const Camera& b, double weight);

/// (1 − weight)·a + weight·b per texel; a alone at weight 0 and b alone at 1 (exact copies).
Image blendImages(const Image& a, const Image& b, double weight);

/// The first and last key's times (0, 0 without keys).
std::pair<double, double> pathSpan(const std::vector<StylizerKeyframe>& keys);

/// The times of a sequence from `start` to `end` at `fps` frames a second: start + i/fps, the
/// last at most `end` (a span of whole frames ends on `end`). InvalidArgument for fps outside
/// (0, 240], end before start or more than `maxFrames` frames.
std::vector<double> sequenceTimes(double start, double end, double fps, size_t maxFrames);

/// Throws InvalidArgument naming the first time of `times` whose interpolated camera is degenerate
/// (two keys' up vectors opposed, the eye passing through the target): checked before a sequence
/// starts, not when it reaches that frame.
void checkPathCameras(const StylizerScene& scene, const std::vector<double>& times);

/// The scene at `time`: its time set and, on a path, the camera interpolated. The TF is left to
/// the stylizer (it blends the keys' compiled TFs, anchored constraints found per key).
StylizerScene sceneAtTime(const StylizerScene& scene, double time);

}  // namespace volstyle::core
