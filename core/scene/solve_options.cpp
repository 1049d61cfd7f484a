#include "core/scene/solve_options.h"

#include <algorithm>
#include <cmath>
#include <ostream>

#include "core/base/errors.h"

namespace volstyle::core {

const char* unknownName(Unknown u) {
    switch (u) {
        case Unknown::Emission: return "emission";
        case Unknown::Albedo: return "albedo";
        case Unknown::EmissionAlbedo: return "emission+albedo";
        case Unknown::Extinction: return "extinction";
    }
    return "?";
}

std::ostream& operator<<(std::ostream& out, StopReason r) { return out << stopReasonName(r); }

std::vector<FieldProblem> SolveOptions::check() const {
    std::vector<FieldProblem> out;
    auto weight = [&](double w, const char* name) {
        if (!(w >= 0 && w <= 1e9)) out.push_back({std::string("regularization/") + name, "must be in [0, 1e9]"});
    };
    auto weights = [&](const Regularization& r, const std::string& prefix) {
        weight(r.laplacian, (prefix + "laplacian").c_str());
        weight(r.l2, (prefix + "l2").c_str());
        weight(r.towardOne, (prefix + "toward_one").c_str());
    };
    weights(regularization, "");
    if (!(prior.weight >= 0 && prior.weight <= 1e9)) out.push_back({"prior/weight", "must be in [0, 1e9]"});
    if (prior.weight > 0 && !prior.values) out.push_back({"prior/values", "a prior with a weight needs its values"});
    if (prior.weight > 0 && (resolution || coarseIterations > 0))
        out.push_back({"prior", "a prior lives on the volume's own grid: no resolution, no coarse iterations"});
    if (emissionRegularization) weights(*emissionRegularization, "emission/");
    if (albedoRegularization) weights(*albedoRegularization, "albedo/");
    if (maxIterations < 1 || maxIterations > 10000) out.push_back({"max_iterations", "must be in [1, 10000]"});
    if (coarseIterations < 0 || coarseIterations > 1000) out.push_back({"coarse_iterations", "must be in [0, 1000]"});
    if (!(visibleChange >= 0) || !std::isfinite(visibleChange)) out.push_back({"visible_change", "must be a finite number >= 0"});
    if (!(tolerance >= 0 && tolerance < 1)) out.push_back({"tolerance", "must be in [0, 1)"});
    if (auto p = stepProblem(stepVoxels)) out.push_back(*p);
    if (resolution && (resolution->x < 1 || resolution->y < 1 || resolution->z < 1 || resolution->x > 1024 ||
                       resolution->y > 1024 || resolution->z > 1024))
        out.push_back({"resolution", "each size must be in [1, 1024]"});
    if (unknown == Unknown::Extinction) {
        if (!mediumRadiance) {
            out.push_back({"medium_radiance", "is required for an extinction solve: L_m, the radiance the medium shows where it is opaque (TVCG Sec. 4.2.4)"});
        } else if (!(std::isfinite(mediumRadiance->x) && std::isfinite(mediumRadiance->y) &&
                     std::isfinite(mediumRadiance->z) && minComponent(*mediumRadiance) >= 0)) {
            out.push_back({"medium_radiance", "must be finite and >= 0"});
        }
    } else if (mediumRadiance) {
        out.push_back({"medium_radiance", "applies to extinction solves only"});
    }
    if (lights.lobes < 0 || lights.lobes > kMaxLobes) out.push_back({"lights/lobes", "must be in [1, 256] (0: the lighting's)"});
    if (lights.rounds < 1 || lights.rounds > 100) out.push_back({"lights/rounds", "must be in [1, 100]"});
    if (lights.solve && lights.withVolume && unknown == Unknown::Extinction)
        out.push_back({"unknowns", "lights go with emission and/or albedo, not extinction"});
    return out;
}

const Regularization& SolveOptions::regularizationFor(Unknown block) const {
    if (block == Unknown::Emission && emissionRegularization) return *emissionRegularization;
    if (block == Unknown::Albedo && albedoRegularization) return *albedoRegularization;
    return regularization;
}

void SolveOptions::validate() const {
    auto problems = check();
    if (problems.empty()) return;
    std::string msg;
    for (const auto& p : problems) msg += (msg.empty() ? "" : "; ") + p.field + ": " + p.message;
    throw InvalidArgument("solve options: " + msg);
}

void SolveView::validate() const {
    const SolveView& v = *this;
    const std::string name = "view '" + v.name + "'";
    try {
        v.camera.validate();
    } catch (const InvalidArgument& e) {
        throw InvalidArgument(name + ": " + e.what());
    }
    if (v.target.width != v.camera.width || v.target.height != v.camera.height)
        throw InvalidArgument(name + ": the target is " + std::to_string(v.target.width) + "x" +
                              std::to_string(v.target.height) + " but the camera renders " +
                              std::to_string(v.camera.width) + "x" + std::to_string(v.camera.height));
    if (size_t bad = v.target.countNonFinite())
        throw InvalidArgument(name + ": the target has " + std::to_string(bad) + " non-finite (NaN/Inf) values");
    if (v.weights) {
        if (v.weights->width != v.target.width || v.weights->height != v.target.height)
            throw InvalidArgument(name + ": the weight image size differs from the target's");
        if (size_t bad = v.weights->countNonFinite())
            throw InvalidArgument(name + ": the weight image has " + std::to_string(bad) + " non-finite values");
    }
    if (v.background) {
        if (v.background->width != v.camera.width || v.background->height != v.camera.height)
            throw InvalidArgument(name + ": the background plate is " + std::to_string(v.background->width) + "x" +
                                  std::to_string(v.background->height) + " but the camera renders " +
                                  std::to_string(v.camera.width) + "x" + std::to_string(v.camera.height));
        if (size_t bad = v.background->countNonFinite())
            throw InvalidArgument(name + ": the background plate has " + std::to_string(bad) + " non-finite values");
    }
}

Lighting SolveView::lightingFor(const Lighting& lighting) const {
    Lighting l = lighting;
    if (background) l.background.plate = background;
    return l;
}


double viewRms(const Vec3d& r2, const Vec3d& weightSum, const Vec3d& viewWeightSum) {
    double total = 0;
    int channels = 0;
    for (int c = 0; c < 3; ++c) {
        if (viewWeightSum[c] <= 0) continue;
        total += std::sqrt(std::max(0.0, r2[c] * weightSum[c] / viewWeightSum[c]));
        ++channels;
    }
    return channels ? total / channels : 0.0;
}

}  // namespace volstyle::core
