#include "core/stylize/stylizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gl/object.h"
#include "core/gl/readback_ring.h"
#include "core/gl/shader_builder.h"
#include "core/render/gl_convert.h"
#include "core/shaders/layout.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/light_map.h"
#include "core/stylize/medium_gpu.h"
#include "core/stylize/morphology_gpu.h"
#include "core/stylize/stylizer_passes.h"
#include "core/stylize/tf_anchors.h"

namespace volstyle::core {

namespace {

/// A frame's render targets up to this size stay in the device's cache for the next frame (a
/// 1080p frame's are about 170 MB... see StylizerTargets::bytes); larger ones are freed once read.
constexpr size_t kKeptFrameBytes = size_t(64) << 20;

/// The hole noise's threshold for a manipulation's probability (a CPU calibration of the noise,
/// shadow_edits.h), made once per setting and kept in the device's cache with the other derived data.
float holeThresholdFor(GpuDevice& device, const Manipulation& m) {
    char key[128];
    std::snprintf(key, sizeof key, "stylizer-hole-threshold/%a/%d/%a/%u", m.holeProbability, m.holeOctaves, m.holePersistence, m.holeSeed);
    auto cached = device.cache().find<float>(key);
    if (!cached)
        cached = device.cache().insert(key, std::make_shared<const float>(holeThreshold(m.holeProbability, m.holeOctaves, m.holePersistence, m.holeSeed)));
    return *cached;
}

}  // namespace

Stylizer::Stylizer(GpuDevice& device) : m_device(device) {}
Stylizer::~Stylizer() = default;

double Stylizer::estimatedLookups(const StylizerScene& scene, const StylizeSettings& settings) {
    // A pick shades its one pixel, unless anchored constraints need the whole frame's AOVs.
    bool anchored = false;
    for (const TransferFunction* tf : scene.transferFunctions()) anchored = anchored || tf->hasAnchors();
    const bool onePixel = settings.pick && settings.pickOnly && !anchored;
    const double pixels = onePixel ? 1.0 : double(scene.camera.width) * scene.camera.height;
    const double texels = double(scene.light.shadowMapSize) * scene.light.shadowMapSize;
    double lookups = pixels * (settings.method == VisibilityMethod::Naive ? settings.steps : kAcceleratedLookupsPerRay);
    if (scene.light.type == StylizerLightType::Spot) lookups += pixels * settings.spotSteps;
    if (scene.volume) lookups += pixels * 3.0 * scene.volume->steps;  // a shadow-map and two texture lookups a step
    // A TF with anchored constraints is compiled for every frame: about 4 µs a texel and
    // diffusion layer on one core (bench/tf_bench), some 400 lookups' worth.
    for (const TransferFunction* tf : scene.transferFunctions()) {
        if (!tf->hasAnchors()) continue;
        double diffusion = 0;
        for (const TfLayer& l : tf->layers) diffusion += l.kind == TfLayerKind::Diffusion ? 1 : 0;
        lookups += 400.0 * tf->width * tf->height * diffusion;
    }
    const LightMap map = lightMapOf(scene);
    for (size_t i = 0; i < scene.occluders.size(); ++i) {
        const Manipulation& m = scene.occluders[i].manipulation;
        if (!m.any()) continue;
        double perTexel = 4;  // drawn alone, copied, folded in
        if (m.closingRadius > 0) perTexel += m.closingShape == MorphShape::Disc && m.closingRadius <= kExactDiscRadius ? 6.0 * (2 * m.closingRadius + 1) : 16;
        if (m.dilationLength > 0) perTexel += dilationTexels(map, scene, i) + (m.erosionPx > 0 ? 6 : 0);
        if (m.holeProbability > 0) perTexel += 8.0 * m.holeOctaves;
        lookups += texels * perTexel;
    }
    return lookups;
}

double Stylizer::measureLookupsPerSecond() {
    StylizerScene probe = builtinForest();
    probe.camera.width = 320;
    probe.camera.height = 180;
    StylizeSettings settings;
    settings.method = VisibilityMethod::Naive;
    settings.steps = 256;
    settings.readShadowMaps = false;
    (void)render(probe, settings);  // compiles the kernels: not part of a frame's cost
    double best = 1e300;
    for (int i = 0; i < 2; ++i) {
        const auto t = Clock::now();
        (void)render(probe, settings);
        best = std::min(best, msSince(t) / 1000.0);
    }
    return estimatedLookups(probe, settings) / std::max(best, 1e-6);
}

StylizedFrame Stylizer::render(const StylizerScene& scene, const StylizeSettings& settings, GpuVolume* medium,
                               const DisplayReadback* display) {
    scene.validate();
    // The TFs to blend, weighted: the two keys' around the scene's time on a path, else its own.
    std::vector<std::pair<TransferFunction, double>> tfs;
    if (!scene.keyframes.empty() && scene.keyframes.front().transferFunction) {
        const PathPosition at = pathPosition(scene.keyframes, scene.time);
        tfs.push_back({*scene.keyframes[at.before].transferFunction, 1 - at.weight});
        if (at.weight > 0) tfs.push_back({*scene.keyframes[at.after].transferFunction, at.weight});
    } else if (scene.transferFunction) {
        tfs.push_back({*scene.transferFunction, 1});
    }
    const bool anchored = std::any_of(tfs.begin(), tfs.end(), [](const auto& t) { return t.first.hasAnchors(); });
    // The TF the frame applies: compiled where it is layers (anchors moved first), blended.
    auto blended = [&] {
        TransferFunction out = tfs.front().first;
        for (auto& [tf, w] : tfs)
            if (!tf.layers.empty() && (!tf.image || tf.hasAnchors())) compileTransferFunction(tf);
        out.layers.clear();
        out.image = tfs.size() == 1 ? tfs.front().first.image
                                    : std::make_shared<const Image>(blendImages(*tfs[0].first.image, *tfs[1].first.image, tfs[1].second));
        return out;
    };
    StylizerScene s = scene;
    s.transferFunction.reset();
    if (!anchored) {
        if (!tfs.empty()) s.transferFunction = blended();
        StylizedFrame f = renderPass(s, settings, medium, display);
        f.transferFunction = s.transferFunction;
        return f;
    }
    // Anchored constraints: where they are depends on this frame's V̄ and depths, so the frame is
    // rendered without the TF (and with its AOVs) and the TF applied to it.
    StylizeSettings withAovs = settings;
    withAovs.readAovs = true;
    withAovs.pickOnly = false;  // the anchors read the AOVs where they are
    StylizedFrame f = renderPass(s, withAovs, medium);
    const auto t = Clock::now();
    for (auto& [tf, w] : tfs) resolveAnchors(tf, scene, f);
    f.transferFunction = blended();
    applyTransferFunction(*f.transferFunction, f);
    if (settings.pick && settings.pickOnly)
        for (Image* img : {&f.frame, &f.scattering, &f.averageVisibility, &f.linearDepth}) {
            Image one(1, 1);
            std::copy_n(img->pixel(settings.pick->x, settings.pick->y), 4, one.rgba.data());
            *img = std::move(one);
        }
    const double ms = msSince(t);
    f.shadeMs += ms, f.totalMs += ms;
    return f;
}

StylizedFrame Stylizer::renderPass(const StylizerScene& scene, const StylizeSettings& settings, GpuVolume* medium,
                                   const DisplayReadback* display) {
    VOLSTYLE_CHECK(m_device.isOwnedByThisThread(), ==, true);  // the scene: validated by render()
    settings.validate();
    if (settings.pick && !(settings.pick->x >= 0 && settings.pick->y >= 0 && settings.pick->x < scene.camera.width &&
                           settings.pick->y < scene.camera.height))
        throw InvalidArgument("/x, /y: the pixel must be inside the " + std::to_string(scene.camera.width) + "×" +
                              std::to_string(scene.camera.height) + " image");
    const auto t0 = Clock::now();
    const LightMap map = lightMapOf(scene);
    const auto targets = stylize::targetsFor(m_device, scene.light.shadowMapSize, scene.camera.width, scene.camera.height,
                                             settings.method == VisibilityMethod::Accelerated, kKeptFrameBytes);
    stylize::Frame f{m_device, scene, settings, map, *targets, {}, stylize::frameParams(scene, settings, map)};
    for (const Occluder& o : scene.occluders) f.meshes.push_back(stylize::gpuMesh(m_device, o.mesh));
    StylizedFrame out;
    // 1–2. The light's shadow maps: the unmodified one, then the scattering's with the edits.
    auto t = Clock::now();
    stylize::shadowMaps(f);
    stylize::shadowEdits(f, [this](const Manipulation& m) { return holeThresholdFor(m_device, m); }, out);
    m_device.finish();
    out.shadowMs = msSince(t);
    // 3. The min-max mipmap (accelerated V̄).
    t = Clock::now();
    stylize::minMax(f, out);
    m_device.finish();
    out.mipmapMs = msSince(t);
    // 4. The camera's G-buffer.
    t = Clock::now();
    stylize::gBuffer(f, out);
    m_device.finish();
    out.gbufferMs = msSince(t);
    // 5. Per pixel: V̄ and the frame.
    t = Clock::now();
    stylize::shade(f, [&](layout::StylizeParams& p) { (void)bindStylizerMedium(m_device, scene.volume, medium, p); }, out);
    out.shadeMs = msSince(t);
    // 6. What was asked for, back to the CPU.
    t = Clock::now();
    if (display && display->ring) stylize::readBackDisplay(f, *display, out);
    else stylize::readBack(f, out);
    out.readbackMs = msSince(t);
    out.totalMs = msSince(t0);
    if (glGetError() == GL_OUT_OF_MEMORY) {
        if (out.displaySlot >= 0) display->ring->release(out.displaySlot);  // nobody will read it
        throw OutOfMemory("out of GPU memory while stylizing");
    }
    return out;
}

}  // namespace volstyle::core
