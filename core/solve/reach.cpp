#include "core/solve/reach.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/base/stopwatch.h"
#include "core/render/gpu_volume.h"
#include "core/render/renderer.h"

namespace volstyle::core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Below this coverage (1 − transmittance) no unknown inside the medium changes a pixel.
constexpr float kMinCoverage = 1e-3f;
/// A suggestion is made when the chosen unknowns leave more than this share of the residual out
/// of reach and another choice leaves at most half as much.
constexpr double kSignificantShare = 0.1;

/// Per-pixel weights as the solver takes them: target alpha × the weight image's first channel.
std::vector<double> pixelWeights(const SolveView& v) {
    std::vector<double> w(v.target.pixelCount());
    for (size_t i = 0; i < w.size(); ++i)
        w[i] = std::max(0.0f, v.target.rgba[4 * i + 3]) * (v.weights ? std::max(0.0f, v.weights->rgba[4 * i]) : 1.0f);
    return w;
}


/// `lo` with +inf wherever the pixel is covered by the medium (what added emission can reach).
Image openAbove(const Image& lo, const Image& coverage) {
    Image hi = lo;
    for (size_t i = 0; i < hi.pixelCount(); ++i)
        if (coverage.rgba[4 * i + 3] > kMinCoverage)
            for (int c = 0; c < 3; ++c) hi.rgba[4 * i + size_t(c)] = std::numeric_limits<float>::infinity();
    return hi;
}

/// Per-channel min and max of two images.
std::pair<Image, Image> between(const Image& a, const Image& b) {
    Image lo = a, hi = a;
    for (size_t i = 0; i < a.rgba.size(); ++i) lo.rgba[i] = std::min(a.rgba[i], b.rgba[i]), hi.rgba[i] = std::max(a.rgba[i], b.rgba[i]);
    return {lo, hi};
}

/// The interval each candidate can reach at every pixel of a view.
std::pair<Image, Image> reachable(Unknown u, const ViewRenders& r, const std::optional<Vec3d>& mediumRadiance) {
    switch (u) {
        case Unknown::Emission: return {r.noEmission, openAbove(r.noEmission, r.now)};
        case Unknown::Albedo: return between(r.albedo0, r.albedo1);
        case Unknown::EmissionAlbedo: return {r.neither, openAbove(r.neither, r.now)};
        default: {  // extinction: between L_m (opaque) and the background (clear)
            Image lm = r.background;
            const Vec3d m = mediumRadiance.value_or(Vec3d(0.0));
            for (size_t i = 0; i < lm.pixelCount(); ++i)
                for (int c = 0; c < 3; ++c) lm.rgba[4 * i + size_t(c)] = float(m[c]);
            return between(lm, r.background);
        }
    }
}

std::string unknownsName(Unknown u) { return u == Unknown::EmissionAlbedo ? "emission,albedo" : unknownName(u); }

}  // namespace

double unreachableRms(const Image& target, const std::vector<double>& weights, const Image& lo, const Image& hi) {
    double total = 0;
    int channels = 0;
    for (int c = 0; c < 3; ++c) {
        double sum = 0, weightSum = 0;
        for (size_t i = 0; i < target.pixelCount(); ++i) {
            const size_t k = 4 * i + size_t(c);
            const double t = target.rgba[k];
            const double d = t < lo.rgba[k] ? lo.rgba[k] - t : (t > hi.rgba[k] ? t - hi.rgba[k] : 0.0);
            sum += weights[i] * d * d;
            weightSum += weights[i];
        }
        if (weightSum <= 0) continue;
        total += std::sqrt(sum / weightSum);
        ++channels;
    }
    return channels ? total / channels : 0.0;
}

namespace {

/// a + sign·b per pixel and channel; alpha from a.
Image combine(const Image& a, const Image& b, float sign = -1.0f) {
    Image out = a;
    for (size_t i = 0; i < out.pixelCount(); ++i)
        for (size_t k = 4 * i; k < 4 * i + 3; ++k) out.rgba[k] = a.rgba[k] + sign * b.rgba[k];
    return out;
}

}  // namespace

std::vector<std::shared_ptr<const ViewRenders>> renderBounds(GpuDevice& device, GpuVolume& gpu, const Lighting& lighting,
                                      const std::vector<SolveView>& views, const SolveOptions& options, bool withAlbedoOne,
                                      const WorkBudget& budget) {
    RenderSettings settings;
    settings.stepVoxels = options.stepVoxels;
    settings.exactTraversal = options.exactTraversal;
    Renderer renderer(device);
    std::vector<ViewRenders> out(views.size());
    for (size_t v = 0; v < views.size(); ++v) {
        // One march per view: the scattering at albedo 1 comes from the same rays (issue #40:
        // a second render of a white volume was half of a first solve's renders).
        const auto t0 = Clock::now();
        const RenderLayers l = renderer.renderLayers(gpu, views[v].camera, views[v].lightingFor(lighting), settings, nullptr, budget,
                                                     withAlbedoOne);
        ViewRenders& r = out[v];
        r.renderMs = msSince(t0);
        r.now = l.beauty;
        r.background = l.background;
        r.noEmission = combine(l.beauty, l.emission);
        r.albedo0 = combine(l.beauty, l.scattering);
        r.neither = combine(r.noEmission, l.scattering);
        if (withAlbedoOne) r.albedo1 = combine(r.albedo0, l.scatteringAtAlbedoOne, 1.0f);
    }
    std::vector<std::shared_ptr<const ViewRenders>> shared;
    for (auto& r : out) shared.push_back(std::make_shared<const ViewRenders>(std::move(r)));
    return shared;
}

/// The unknowns' part of analyzeReach: what the chosen and the other unknowns leave out of reach.
void analyzeReachOfUnknowns(const std::vector<std::shared_ptr<const ViewRenders>>& renders, const std::vector<SolveView>& views,
                            const SolveOptions& options, ReachReport& reach);

void analyzeReach(GpuDevice& device, const Volume& volume, const Lighting& lighting, const std::vector<SolveView>& views,
                  const SolveOptions& options, SolveReport& report) {
    const auto t0 = Clock::now();
    GpuVolume gpu(volume);
    const auto renders = renderBounds(device, gpu, lighting, views, options, true);
    analyzeReach(renders, views, options, report);
    report.reach.ms = msSince(t0);
}

void analyzeReach(const std::vector<std::shared_ptr<const ViewRenders>>& renders, const std::vector<SolveView>& views, const SolveOptions& options,
                  SolveReport& report) {
    ReachReport& reach = report.reach;
    for (const SolveView& v : views) reach.clippedPixels += v.clippedPixels;
    analyzeReachOfUnknowns(renders, views, options, reach);
    if (reach.clippedPixels > 0) {  // said, never blamed on the unknowns: those pixels carry no weight
        const std::string clipped = fmt::format(
            "{} pixels of the targets were left out because the picture under the paint was clipped there (white, 255 in an 8-bit image): "
            "paint over a linear EXR render to use them",
            reach.clippedPixels);
        reach.advice = reach.advice.empty() ? clipped : reach.advice + "; " + clipped;
    }
}

void analyzeReachOfUnknowns(const std::vector<std::shared_ptr<const ViewRenders>>& renders, const std::vector<SolveView>& views,
                            const SolveOptions& options, ReachReport& reach) {
    const Unknown candidates[] = {Unknown::Emission, Unknown::Albedo, Unknown::EmissionAlbedo};
    std::map<Unknown, double> meanUnreachable;
    double meanChosen = 0, meanResidual = 0;
    for (size_t v = 0; v < views.size(); ++v) {
        const std::vector<double> w = pixelWeights(views[v]);
        auto [lo, hi] = reachable(options.unknown, *renders[v], options.mediumRadiance);
        const double chosen = unreachableRms(views[v].target, w, lo, hi);
        reach.unreachableRms.push_back(chosen);
        meanChosen += chosen / double(views.size());
        meanResidual += unreachableRms(views[v].target, w, renders[v]->now, renders[v]->now) / double(views.size());
        std::vector<std::pair<Unknown, double>> alternatives;
        for (Unknown u : candidates) {
            auto [clo, chi] = reachable(u, *renders[v], options.mediumRadiance);
            const double x = u == options.unknown ? chosen : unreachableRms(views[v].target, w, clo, chi);
            alternatives.emplace_back(u, x);
            meanUnreachable[u] += x / double(views.size());
        }
        reach.alternatives.push_back(std::move(alternatives));
    }
    if (meanResidual <= 0 || meanChosen <= kSignificantShare * meanResidual) return;
    // The candidate that leaves least out of reach, the simplest first on ties.
    Unknown best = options.unknown;
    double bestValue = meanChosen;
    for (Unknown u : candidates)
        if (meanUnreachable[u] < bestValue * 0.999) best = u, bestValue = meanUnreachable[u];
    std::string advice = fmt::format(
        "{:.0f}% of the paint's difference (RMS {:.3g} of {:.3g}) is out of reach of {}: {}", 100 * meanChosen / meanResidual,
        meanChosen, meanResidual, unknownsName(options.unknown),
        options.unknown == Unknown::Emission ? "emission only adds light, so it cannot darken or change a colour toward less light"
        : options.unknown == Unknown::Albedo ? "albedo only moves a pixel between the medium's black and white scattering"
        : options.unknown == Unknown::EmissionAlbedo ? "no unknown can darken below the medium's own shadow or change uncovered pixels"
                                                     : "extinction keeps each pixel between the medium radiance and the background");
    if (best != options.unknown && bestValue <= 0.5 * meanChosen) {
        reach.suggestion = best;
        advice += fmt::format("; solving for {} would leave RMS {:.3g} out of reach", unknownsName(best), bestValue);
    }
    reach.advice = advice;
}

}  // namespace volstyle::core
