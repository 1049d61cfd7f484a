#include "core/scene/field_problem.h"

#include "core/base/errors.h"

namespace volstyle::core {

void throwIfAny(const char* what, const std::vector<FieldProblem>& problems) {
    if (problems.empty()) return;
    std::string msg;
    for (const auto& p : problems) msg += (msg.empty() ? "" : "; ") + std::string(what) + "." + p.field + ": " + p.message;
    throw InvalidArgument(msg);
}

}  // namespace volstyle::core
