#include "core/stylize/tf_anchors.h"

#include <algorithm>

#include "core/base/errors.h"

namespace volstyle::core {

bool TransferFunction::hasAnchors() const {
    for (const TfLayer& l : layers)
        for (const TfConstraint& c : l.constraints)
            if (c.anchor) return true;
    return false;
}

TfPosition tfPositionAt(const TransferFunction& tf, const StylizedFrame& frame, int x, int y) {
    const double s = frame.linearDepth.pixel(x, y)[0];
    return {std::clamp(double(frame.averageVisibility.pixel(x, y)[0]), 0.0, 1.0),
            std::clamp((s - tf.depthNear) / (tf.depthFar - tf.depthNear), 0.0, 1.0)};
}

namespace {

const Occluder* followed(const StylizerScene& scene, const std::string& name) {
    for (const Occluder& o : scene.occluders)
        if (o.name == name) return &o;
    throw InvalidArgument("a TF anchor follows '" + name + "', which is no occluder of the scene");
}

}  // namespace

Vec3d anchorWorldPosition(const StylizerScene& scene, const TfAnchor& anchor) {
    if (anchor.follow.empty()) return anchor.position;
    return followed(scene, anchor.follow)->worldFromObject.applyPoint(anchor.position);
}

TfAnchor anchorAtPixel(const StylizerScene& scene, int x, int y, double s, int occluder) {
    const Camera& cam = scene.camera;
    const Vec3d world = cam.eye + cam.rayDirection(x, y) * s;
    if (occluder < 0 || occluder >= int(scene.occluders.size())) return {world, ""};
    const Occluder& o = scene.occluders[size_t(occluder)];
    return {o.worldFromObject.inverseAffine().applyPoint(world), o.name};
}

int resolveAnchors(TransferFunction& tf, const StylizerScene& scene, const StylizedFrame& frame) {
    int moved = 0;
    for (TfLayer& l : tf.layers)
        for (TfConstraint& c : l.constraints) {
            if (!c.anchor) continue;
            const auto pixel = scene.camera.project(anchorWorldPosition(scene, *c.anchor));
            if (!pixel) continue;
            const TfPosition at = tfPositionAt(tf, frame, pixel->x, pixel->y);
            c.vBar = at.vBar, c.depth = at.depth;
            ++moved;
        }
    return moved;
}

void compileTransferFunction(TransferFunction& tf, TfCompileStats* stats) {
    if (tf.layers.empty()) return;
    tf.image = std::make_shared<const Image>(compileTfLayers(tf.layers, tf.width, tf.height, stats));
}

void applyTransferFunction(const TransferFunction& tf, StylizedFrame& frame) {
    VOLSTYLE_CHECK(bool(tf.image), ==, true);
    const bool multiply = tf.mode == TransferFunction::Mode::Multiply;
    for (int y = 0; y < frame.frame.height; ++y)
        for (int x = 0; x < frame.frame.width; ++x) {
            const TfPosition at = tfPositionAt(tf, frame, x, y);
            const auto F = sampleTransferFunction(*tf.image, at.vBar, at.depth);
            float* out = frame.frame.pixel(x, y);
            const float* scattering = frame.scattering.pixel(x, y);
            for (int c = 0; c < 3; ++c) {
                const double styled = multiply ? F[size_t(c)] * scattering[c] : F[size_t(c)] * F[3];
                out[c] += float(styled - scattering[c]);
            }
        }
}

}  // namespace volstyle::core
