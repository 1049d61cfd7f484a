#pragma once
/// \file solve_json.h
/// Solver options as JSON (SPEC §2), shared by the HTTP API and `volstyle solve --options`:
///
///   {"unknowns": ["emission","albedo"], "basis": "trilinear"|"box",
///    "regularization": {"laplacian": 0.002, "l2": 0, "toward_one": 0},
///    "max_iterations": 30, "tolerance": 1e-4, "step": 0.5, "traversal": "march"|"exact",
///    "hull": "extinction"|"none",
///    "resolution": {"emission": [64,64,64]}, "medium_radiance": [r,g,b], "views": ["v1","v3"]}
///
/// Every field is optional. `unknowns` is one of ["emission"], ["albedo"], ["emission","albedo"],
/// ["extinction"]. `resolution` may name each unknown; a joint solve needs one grid for both.

#include <nlohmann/json.hpp>

#include <string>

#include "core/scene/solve_options.h"
#include "protocol/validation.h"

namespace volstyle::protocol {

/// Throws ValidationError listing every invalid field. Starts from `base` (defaults or CLI flags).
core::SolveOptions solveOptionsFromJson(const nlohmann::json& j, const std::string& path = "",
                                        core::SolveOptions base = {});
nlohmann::json solveOptionsToJson(const core::SolveOptions& options);
nlohmann::json solveReportToJson(const core::SolveReport& report);
nlohmann::json solveProgressToJson(const core::SolveProgress& progress);

/// "emission", "albedo", "emission,albedo" (or with +), "extinction" → the unknown.
std::optional<core::Unknown> parseUnknowns(const std::vector<std::string>& names);

}  // namespace volstyle::protocol
