#include "core/scene/render_settings.h"

#include <sstream>

namespace volstyle::core {

std::optional<FieldProblem> stepProblem(double stepVoxels) {
    if (stepVoxels >= kMinStepVoxels && stepVoxels <= kMaxStepVoxels) return std::nullopt;
    std::ostringstream m;
    m << "must be in [" << kMinStepVoxels << ", " << kMaxStepVoxels << "] voxels, got " << stepVoxels;
    return FieldProblem{"step", m.str()};
}

void RenderSettings::validate() const {
    std::vector<FieldProblem> out;
    if (auto p = stepProblem(stepVoxels)) out.push_back(*p);
    if (!(terminationThreshold >= 0 && terminationThreshold < 1))
        out.push_back({"termination_threshold", "must be in [0, 1)"});
    throwIfAny("render", out);
}

}  // namespace volstyle::core
