#include "core/translucent/translucent_settings.h"

#include <cmath>

#include "core/base/errors.h"

namespace volstyle::core {

std::vector<FieldProblem> TranslucentSettings::check() const {
    std::vector<FieldProblem> out;
    if (!(sliceSpacing > 0 && sliceSpacing <= 8)) out.push_back({"slice_spacing", "must be in (0, 8] voxels"});
    if (lightBufferSize < 16 || lightBufferSize > 4096) out.push_back({"light_buffer", "must be in [16, 4096] texels"});
    if (!(indirect.blurAngleDeg >= 0 && indirect.blurAngleDeg < 90)) out.push_back({"indirect/blur_angle_deg", "must be in [0, 90) degrees"});
    if (!(std::isfinite(indirect.extinction) && indirect.extinction >= 0))
        out.push_back({"indirect/extinction", "must be finite and >= 0"});
    for (int c = 0; c < 3; ++c)
        if (!(indirect.transportColor[c] > 0 && indirect.transportColor[c] <= 1)) {
            out.push_back({"indirect/transport_color", "must be RGB in (0, 1]"});
            break;
        }
    if (!(surfaceShading >= 0 && surfaceShading <= 1)) out.push_back({"surface_shading", "must be in [0, 1]"});
    for (auto& p : perturbation.check()) out.push_back({"perturbation/" + p.field, std::move(p.message)});
    return out;
}

void TranslucentSettings::validate() const {
    const auto problems = check();
    if (problems.empty()) return;
    std::string message;
    for (const auto& p : problems) message += (message.empty() ? "" : "; ") + std::string("translucent.") + p.field + ": " + p.message;
    throw InvalidArgument(message);
}

}  // namespace volstyle::core
