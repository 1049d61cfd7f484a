#pragma once
/// \file field_problem.h
/// How a scene value reports what is wrong with it: every problem with the JSON field it belongs
/// to (protocol/ maps the field to a JSON Pointer), from one check() per value.

#include <string>
#include <vector>

namespace volstyle::core {

/// A field of a parameter struct and what is wrong with it (protocol/ maps it to a JSON Pointer).
struct FieldProblem {
    std::string field;    ///< e.g. "fov_y_deg", "lights/0/irradiance"
    std::string message;
};

/// Throws InvalidArgument listing `problems` ("what.field: message; …"); nothing when empty.
void throwIfAny(const char* what, const std::vector<FieldProblem>& problems);

}  // namespace volstyle::core
