#include "core/stylize/keyframes.h"

#include <cmath>
#include <string>

#include "core/base/errors.h"

namespace volstyle::core {

PathPosition pathPosition(const std::vector<StylizerKeyframe>& keys, double time) {
    if (keys.empty() || time <= keys.front().time) return {};
    const size_t last = keys.size() - 1;
    if (time >= keys[last].time) return {last, last, 0};
    size_t i = 0;
    while (keys[i + 1].time <= time) ++i;
    const double w = (time - keys[i].time) / (keys[i + 1].time - keys[i].time);
    return {i, i + 1, w};
}

Camera interpolateCamera(const Camera& a, const Camera& b, double w) {
    if (w <= 0) return a;
    if (w >= 1) {
        Camera c = b;
        c.width = a.width, c.height = a.height;
        return c;
    }
    Camera c = a;
    c.eye = a.eye * (1 - w) + b.eye * w;
    c.target = a.target * (1 - w) + b.target * w;
    c.up = a.up * (1 - w) + b.up * w;
    c.fovYDeg = a.fovYDeg * (1 - w) + b.fovYDeg * w;
    c.nearDist = a.nearDist * (1 - w) + b.nearDist * w;
    c.farDist = a.farDist * (1 - w) + b.farDist * w;
    return c;
}

Image blendImages(const Image& a, const Image& b, double w) {
    if (w <= 0) return a;
    if (w >= 1) return b;
    VOLSTYLE_CHECK(a.rgba.size(), ==, b.rgba.size());
    Image out = a;
    for (size_t i = 0; i < out.rgba.size(); ++i) out.rgba[i] = float((1 - w) * a.rgba[i] + w * b.rgba[i]);
    return out;
}

std::pair<double, double> pathSpan(const std::vector<StylizerKeyframe>& keys) {
    if (keys.empty()) return {0, 0};
    return {keys.front().time, keys.back().time};
}

std::vector<double> sequenceTimes(double start, double end, double fps, size_t maxFrames) {
    if (!(fps > 0 && fps <= 240)) throw InvalidArgument("fps must be in (0, 240]");
    if (!(std::abs(start) <= 1e9 && std::abs(end) <= 1e9)) throw InvalidArgument("start and end must be finite (|t| <= 1e9)");
    if (!(end >= start)) throw InvalidArgument("the sequence ends before it starts");
    const double frames = std::floor((end - start) * fps + 1e-9) + 1;
    if (frames > double(maxFrames))
        throw InvalidArgument("the sequence would have " + std::to_string(size_t(frames)) + " frames, over the limit of " + std::to_string(maxFrames));
    std::vector<double> times;
    for (size_t i = 0; i < size_t(frames); ++i) times.push_back(start + double(i) / fps);
    return times;
}

void checkPathCameras(const StylizerScene& scene, const std::vector<double>& times) {
    if (scene.keyframes.empty()) return;
    for (double t : times) {
        const PathPosition at = pathPosition(scene.keyframes, t);
        try {
            interpolateCamera(scene.keyframes[at.before].camera, scene.keyframes[at.after].camera, at.weight).validate();
        } catch (const InvalidArgument& e) {
            throw InvalidArgument("the path's camera at t = " + std::to_string(t) + " (between keys " + std::to_string(at.before) + " and " +
                                  std::to_string(at.after) + ") is degenerate: " + e.what());
        }
    }
}

StylizerScene sceneAtTime(const StylizerScene& scene, double time) {
    StylizerScene s = scene;
    s.time = time;
    if (!scene.keyframes.empty()) {
        const PathPosition at = pathPosition(scene.keyframes, time);
        s.camera = interpolateCamera(scene.keyframes[at.before].camera, scene.keyframes[at.after].camera, at.weight);
    }
    return s;
}

}  // namespace volstyle::core
