#include "protocol/solve_json.h"

#include <algorithm>
#include <set>

namespace volstyle::protocol {

std::optional<core::Unknown> parseUnknowns(const std::vector<std::string>& names) {
    std::set<std::string> s(names.begin(), names.end());
    if (s == std::set<std::string>{"emission"}) return core::Unknown::Emission;
    if (s == std::set<std::string>{"albedo"}) return core::Unknown::Albedo;
    if (s == std::set<std::string>{"emission", "albedo"}) return core::Unknown::EmissionAlbedo;
    if (s == std::set<std::string>{"extinction"}) return core::Unknown::Extinction;
    return std::nullopt;
}

namespace {

/// "unknowns": ["emission"] … or ["lights", …] (SPEC §8: alone, or with emission and/or albedo).
void unknownsFromJson(JsonReader& r, const nlohmann::json& list, const std::string& path, core::SolveOptions& o) {
    if (!list.is_array()) return r.fail(path, "must be an array such as [\"emission\", \"albedo\"]");
    std::vector<std::string> names;
    const size_t before = r.errors().size();
    for (size_t i = 0; i < list.size(); ++i)
        if (auto s = r.string(list[i], path + "/" + std::to_string(i))) names.push_back(*s);
    const auto lights = std::find(names.begin(), names.end(), "lights");
    o.lights.solve = lights != names.end();
    if (o.lights.solve) names.erase(lights);
    o.lights.withVolume = o.lights.solve && !names.empty();
    if (o.lights.solve && names.empty()) {
        o.unknown = core::Unknown::Emission;  // unused: the volume stays fixed
    } else if (auto u = parseUnknowns(names)) {
        o.unknown = *u;
    } else if (r.errors().size() == before) {
        r.fail(path, "must be [\"emission\"], [\"albedo\"], [\"emission\", \"albedo\"], [\"extinction\"] "
                     "or [\"lights\"] (alone or with emission and/or albedo)");
    }
}

/// "regularization": the shared weights, and per-unknown objects that start from them.
void regularizationFromJson(JsonReader& r, const nlohmann::json& g, const std::string& p, core::SolveOptions& o) {
    if (!r.object(g, p, {"laplacian", "l2", "toward_one", "emission", "albedo"})) return;
    auto weights = [&](const nlohmann::json& w, const std::string& wp, core::Regularization& reg) {
        if (w.contains("laplacian")) reg.laplacian = r.number(w["laplacian"], wp + "/laplacian").value_or(reg.laplacian);
        if (w.contains("l2")) reg.l2 = r.number(w["l2"], wp + "/l2").value_or(reg.l2);
        if (w.contains("toward_one")) reg.towardOne = r.number(w["toward_one"], wp + "/toward_one").value_or(reg.towardOne);
    };
    weights(g, p, o.regularization);
    for (const char* name : {"emission", "albedo"}) {
        if (!g.contains(name) || !r.object(g[name], p + "/" + name, {"laplacian", "l2", "toward_one"})) continue;
        core::Regularization reg = o.regularization;
        weights(g[name], p + "/" + name, reg);
        (std::string(name) == "emission" ? o.emissionRegularization : o.albedoRegularization) = reg;
    }
}

/// "lights": {"lobes", "domain", "rounds", "background"} of a light solve.
void lightsFromJson(JsonReader& r, const nlohmann::json& l, const std::string& path, core::SolveOptions& o) {
    if (!r.object(l, path, {"lobes", "domain", "rounds", "background"})) return;
    if (l.contains("background")) o.lights.background = r.boolean(l["background"], path + "/background").value_or(false);
    if (l.contains("lobes")) {  // 0 is what leaving it out means: sent, it must be a count
        o.lights.lobes = r.integer(l["lobes"], path + "/lobes").value_or(o.lights.lobes);
        if (o.lights.lobes == 0) r.fail(path + "/lobes", "must be in [1, 256] (leave it out for the lighting's own count)");
    }
    if (l.contains("rounds")) o.lights.rounds = r.integer(l["rounds"], path + "/rounds").value_or(o.lights.rounds);
    if (l.contains("domain")) {
        auto d = r.string(l["domain"], path + "/domain");
        if (d == "sphere") o.lights.domain = core::LobeDomain::Sphere;
        else if (d == "upper_hemisphere") o.lights.domain = core::LobeDomain::UpperHemisphere;
        else if (d) r.fail(path + "/domain", "must be 'sphere' or 'upper_hemisphere'");
    }
}

/// "resolution": {"emission"|"albedo"|"extinction": [nx, ny, nz]}, one grid for all.
void resolutionFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, core::SolveOptions& o) {
    if (!r.object(j, path, {"emission", "albedo", "extinction"})) return;
    std::optional<Int3> res;
    for (const auto& [key, value] : j.items()) {
        const std::string p = path + "/" + key;
        if (!value.is_array() || value.size() != 3 || !value[0].is_number_integer() || !value[1].is_number_integer() ||
            !value[2].is_number_integer()) {
            r.fail(p, "must be [nx, ny, nz] integers");
            continue;
        }
        Int3 v{value[0].get<int>(), value[1].get<int>(), value[2].get<int>()};
        if (res && !(*res == v)) r.fail(p, "emission and albedo are solved on one grid: give them the same resolution");
        res = v;
    }
    if (res) o.resolution = res;
}

/// A string field that names one of two choices: `first` sets `flag` to `firstMeans`, `second`
/// to the other.
void choiceFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, const char* first, const char* second, bool firstMeans,
                    bool& flag) {
    auto v = r.string(j, path);
    if (v == first) flag = firstMeans;
    else if (v == second) flag = !firstMeans;
    else if (v) r.fail(path, std::string("must be '") + first + "' or '" + second + "'");
}

/// The scalar fields; their ranges are SolveOptions::check()'s.
void scalarsFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, core::SolveOptions& o) {
    if (j.contains("max_iterations")) o.maxIterations = r.integer(j["max_iterations"], path + "/max_iterations").value_or(o.maxIterations);
    if (j.contains("coarse_iterations")) o.coarseIterations = r.integer(j["coarse_iterations"], path + "/coarse_iterations").value_or(o.coarseIterations);
    if (j.contains("visible_change")) o.visibleChange = r.number(j["visible_change"], path + "/visible_change").value_or(o.visibleChange);
    if (j.contains("local_resolve")) o.localResolve = r.boolean(j["local_resolve"], path + "/local_resolve").value_or(o.localResolve);
    if (j.contains("tolerance")) o.tolerance = r.number(j["tolerance"], path + "/tolerance").value_or(o.tolerance);
    if (j.contains("step")) o.stepVoxels = r.number(j["step"], path + "/step").value_or(o.stepVoxels);
    if (j.contains("medium_radiance")) o.mediumRadiance = r.vec3(j["medium_radiance"], path + "/medium_radiance");
}

}  // namespace

core::SolveOptions solveOptionsFromJson(const nlohmann::json& j, const std::string& path, core::SolveOptions o) {
    JsonReader r;
    if (r.object(j, path, {"unknowns", "basis", "regularization", "max_iterations", "tolerance", "step", "traversal", "hull",
                           "resolution", "medium_radiance", "views", "coarse_iterations", "visible_change", "local_resolve",
                           "lights"})) {
        if (j.contains("unknowns")) unknownsFromJson(r, j["unknowns"], path + "/unknowns", o);
        if (j.contains("basis")) {
            bool trilinear = o.basis == core::BasisType::Trilinear;
            choiceFromJson(r, j["basis"], path + "/basis", "trilinear", "box", true, trilinear);
            o.basis = trilinear ? core::BasisType::Trilinear : core::BasisType::Box;
        }
        if (j.contains("regularization")) regularizationFromJson(r, j["regularization"], path + "/regularization", o);
        if (j.contains("lights")) lightsFromJson(r, j["lights"], path + "/lights", o);
        scalarsFromJson(r, j, path, o);
        if (j.contains("traversal")) choiceFromJson(r, j["traversal"], path + "/traversal", "march", "exact", false, o.exactTraversal);
        if (j.contains("hull")) choiceFromJson(r, j["hull"], path + "/hull", "extinction", "none", true, o.useHull);
        if (j.contains("resolution")) resolutionFromJson(r, j["resolution"], path + "/resolution", o);
        if (j.contains("views")) {
            o.views.clear();
            if (!j["views"].is_array()) r.fail(path + "/views", "must be an array of view ids");
            else if (j["views"].empty()) r.fail(path + "/views", "names no view; leave it out to solve every view with a target");
            else
                for (size_t i = 0; i < j["views"].size(); ++i)
                    if (auto s = r.string(j["views"][i], path + "/views/" + std::to_string(i))) o.views.push_back(*s);
        }
        for (const auto& p : o.check()) r.check(path, p.field, p.message);
    }
    r.throwIfErrors();
    return o;
}

nlohmann::json solveOptionsToJson(const core::SolveOptions& o) {
    nlohmann::json unknowns = o.unknown == core::Unknown::EmissionAlbedo ? nlohmann::json{"emission", "albedo"}
                                                                         : nlohmann::json{core::unknownName(o.unknown)};
    nlohmann::json j = {{"unknowns", unknowns},
                        {"basis", o.basis == core::BasisType::Box ? "box" : "trilinear"},
                        {"regularization", {{"laplacian", o.regularization.laplacian}, {"l2", o.regularization.l2},
                                            {"toward_one", o.regularization.towardOne}}},
                        {"max_iterations", o.maxIterations}, {"tolerance", o.tolerance}, {"step", o.stepVoxels},
                        {"traversal", o.exactTraversal ? "exact" : "march"},
                        {"hull", o.useHull ? "extinction" : "none"}, {"views", o.views},
                        {"coarse_iterations", o.coarseIterations}, {"visible_change", o.visibleChange},
                        {"local_resolve", o.localResolve}};
    for (auto [name, reg] : {std::pair{"emission", &o.emissionRegularization}, std::pair{"albedo", &o.albedoRegularization}})
        if (*reg) j["regularization"][name] = {{"laplacian", (*reg)->laplacian}, {"l2", (*reg)->l2}, {"toward_one", (*reg)->towardOne}};
    if (o.resolution) j["resolution"] = {{o.unknown == core::Unknown::Extinction ? "extinction" : "emission",
                                         {o.resolution->x, o.resolution->y, o.resolution->z}}};
    if (o.mediumRadiance) j["medium_radiance"] = {o.mediumRadiance->x, o.mediumRadiance->y, o.mediumRadiance->z};
    return j;
}

namespace {

std::vector<std::string> unknownNames(core::Unknown u) {
    if (u == core::Unknown::EmissionAlbedo) return {"emission", "albedo"};
    return {core::unknownName(u)};
}

/// {"unreachable_rms": [per view], "alternatives": [[{"unknowns", "unreachable_rms"}, …] per view],
///  "suggested_unknowns": [...] | null, "advice": "…"}
nlohmann::json reachToJson(const core::ReachReport& r) {
    nlohmann::json alternatives = nlohmann::json::array();
    for (const auto& view : r.alternatives) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& [u, rms] : view) list.push_back({{"unknowns", unknownNames(u)}, {"unreachable_rms", rms}});
        alternatives.push_back(list);
    }
    return {{"unreachable_rms", r.unreachableRms}, {"alternatives", alternatives}, {"clipped_pixels", r.clippedPixels},
            {"suggested_unknowns", r.suggestion ? nlohmann::json(unknownNames(*r.suggestion)) : nlohmann::json(nullptr)},
            {"advice", r.advice}, {"ms", r.ms}};
}

}  // namespace

nlohmann::json solveReportToJson(const core::SolveReport& r) {
    nlohmann::json setup = nlohmann::json::array();
    for (const auto& [phase, ms] : r.setupPhases) setup.push_back({{"phase", phase}, {"ms", ms}});
    return {{"setup_ms", r.setupMs()}, {"setup", setup},{"iterations", r.iterations}, {"stop_reason", core::stopReasonName(r.stopReason)}, {"initial_objective", r.initialObjective},
            {"final_objective", r.finalObjective}, {"initial_rms", r.initialRms}, {"final_rms", r.finalRms},
            {"unknowns", r.unknownCount}, {"hull_unknowns", r.hullCount}, {"constraint_pixels", r.constraintPixels},
            {"ignored_pixels", r.ignoredPixels}, {"clamped_pixels", r.clampedPixels}, {"total_ms", r.totalMs},
            {"forward_ms", r.forwardMs}, {"adjoint_ms", r.adjointMs}, {"vector_ms", r.vectorMs}, {"reach", reachToJson(r.reach)},
            {"coarse_iterations", r.coarseIterations}, {"coarse_ms", r.coarseMs},
            {"row_cache", {{"ms", r.rowCacheMs}, {"bytes", r.rowCacheBytes}, {"cached_views", r.cachedViews}, {"written_views", r.writtenViews}}},
            {"local", r.local.active ? nlohmann::json{{"changed_pixels", r.local.changedPixels}, {"unknowns", r.local.unknowns},
                                                      {"pixels", r.local.pixels}}
                                     : nlohmann::json(nullptr)}};
}

nlohmann::json solveProgressToJson(const core::SolveProgress& p) {
    return {{"phase", core::solvePhaseName(p.phase)}, {"iteration", p.iteration}, {"objective", p.objective}, {"rms_per_view", p.rmsPerView},
            {"elapsed_ms", p.elapsedMs}, {"forward_ms", p.forwardMs}, {"adjoint_ms", p.adjointMs},
            {"vector_ms", p.vectorMs}};
}

}  // namespace volstyle::protocol
