#include "protocol/render_json.h"

#include <cstdio>

namespace volstyle::protocol {
namespace {

nlohmann::json toJson(const Vec3d& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace

core::Camera cameraFromJson(const nlohmann::json& j, const std::string& path) {
    JsonReader r;
    core::Camera cam;
    if (r.object(j, path, {"eye", "target", "up", "fov_y_deg", "width", "height", "near", "far"})) {
        for (const char* required : {"eye", "target"})
            if (!j.contains(required)) r.fail(path + "/" + required, "is required");
        if (j.contains("eye")) cam.eye = r.vec3(j["eye"], path + "/eye").value_or(cam.eye);
        if (j.contains("target")) cam.target = r.vec3(j["target"], path + "/target").value_or(cam.target);
        if (j.contains("up")) cam.up = r.vec3(j["up"], path + "/up").value_or(cam.up);
        if (j.contains("fov_y_deg")) cam.fovYDeg = r.number(j["fov_y_deg"], path + "/fov_y_deg").value_or(cam.fovYDeg);
        if (j.contains("width")) cam.width = r.integer(j["width"], path + "/width").value_or(cam.width);
        if (j.contains("height")) cam.height = r.integer(j["height"], path + "/height").value_or(cam.height);
        if (j.contains("near")) cam.nearDist = r.number(j["near"], path + "/near").value_or(cam.nearDist);
        if (j.contains("far")) cam.farDist = r.number(j["far"], path + "/far").value_or(cam.farDist);
        for (const auto& p : cam.check()) {
            if (p.field == "target" || p.field == "up") r.check(path, p.field, p.message, {"eye", "target", "up"});  // eye = target, up ∥ view
            else r.check(path, p.field, p.message);
        }
    }
    r.throwIfErrors();
    return cam;
}

nlohmann::json cameraToJson(const core::Camera& c) {
    nlohmann::json j = {{"eye", toJson(c.eye)}, {"target", toJson(c.target)}, {"up", toJson(c.up)},
                        {"fov_y_deg", c.fovYDeg}, {"width", c.width}, {"height", c.height}};
    if (c.nearDist > 0) j["near"] = c.nearDist;
    if (c.farDist < 1e30) j["far"] = c.farDist;
    return j;
}

namespace {

std::optional<core::DirectionalLight> lightFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path) {
    if (!r.object(j, path, {"direction", "irradiance"})) return std::nullopt;
    core::DirectionalLight l;
    for (const char* required : {"direction", "irradiance"})
        if (!j.contains(required)) r.fail(path + "/" + required, "is required");
    if (j.contains("direction")) l.direction = r.vec3(j["direction"], path + "/direction").value_or(l.direction);
    if (j.contains("irradiance")) l.irradiance = r.vec3(j["irradiance"], path + "/irradiance").value_or(l.irradiance);
    return l;
}

}  // namespace

namespace {

/// "environment": lobes, domain, radiance per lobe, map (CLI only), strength, light_volume_resolution.
void environmentFromJson(JsonReader& r, const nlohmann::json& e, const std::string& ep, bool allowFilePaths, LightingRequest& out) {
    core::EnvironmentLight& env = out.lighting.environment;
    if (!r.object(e, ep, {"lobes", "domain", "radiance", "map", "strength", "light_volume_resolution"})) return;
    if (!e.contains("lobes")) r.fail(ep + "/lobes", "is required: the number of lobes, 1-256");
    else if (auto n = r.integer(e["lobes"], ep + "/lobes")) {
        if (*n < core::kMinLobes || *n > core::kMaxLobes) r.fail(ep + "/lobes", "must be in [1, 256], got " + std::to_string(*n));
        else env.lobes = *n;
    }
    if (e.contains("domain")) {
        const std::string d = r.string(e["domain"], ep + "/domain").value_or("sphere");
        if (d == "upper_hemisphere") env.domain = core::LobeDomain::UpperHemisphere;
        else if (d != "sphere") r.fail(ep + "/domain", "must be 'sphere' or 'upper_hemisphere', got '" + d + "'");
    }
    if (e.contains("radiance")) {
        if (!e["radiance"].is_array()) {
            r.fail(ep + "/radiance", "must be an array of [r,g,b], one per lobe");
        } else {
            for (size_t i = 0; i < e["radiance"].size(); ++i)
                env.radiance.push_back(r.vec3(e["radiance"][i], ep + "/radiance/" + std::to_string(i)).value_or(Vec3d()));
        }
    }
    if (e.contains("map")) {
        const std::optional<std::string> map = r.string(e["map"], ep + "/map");
        if (allowFilePaths) out.environmentLightPath = map;
        else if (map == kSessionMap) out.environmentUsesSessionMap = true;
        else if (map) r.fail(ep + "/map", "file paths are not accepted here; upload the map (PUT /sessions/{sid}/environment) and give \"session\", or give the radiance per lobe");
    }
    if (e.contains("strength")) env.strength = r.number(e["strength"], ep + "/strength").value_or(1);
    if (e.contains("light_volume_resolution"))
        env.lightVolumeResolution = r.integer(e["light_volume_resolution"], ep + "/light_volume_resolution").value_or(64);
    if (!e.contains("radiance") && !e.contains("map")) r.fail(ep, "needs \"radiance\" (one [r,g,b] per lobe) or \"map\"");
    // A map is loaded by the caller (or resolve()): until then, don't let check() ask for one.
    // Radiances given beside it (GET writes the map's projection) are kept as the fallback.
    if ((out.environmentLightPath || out.environmentUsesSessionMap) && env.radiance.empty())
        env.radiance.assign(size_t(std::max(env.lobes, 0)), Vec3d());
}

}  // namespace

namespace {

/// The fields of core::Perturbation at `path` (unknown ones refused); the caller checks the values.
void readPerturbation(JsonReader& r, const nlohmann::json& in, const std::string& pp, core::Perturbation& d) {
    if (!r.object(in, pp, {"amplitude", "frequency", "octaves", "property_amplitude", "seed", "time"})) return;
    if (in.contains("amplitude")) d.amplitude = r.number(in["amplitude"], pp + "/amplitude").value_or(d.amplitude);
    if (in.contains("frequency")) d.frequency = r.number(in["frequency"], pp + "/frequency").value_or(d.frequency);
    if (in.contains("octaves")) d.octaves = r.integer(in["octaves"], pp + "/octaves").value_or(d.octaves);
    if (in.contains("property_amplitude"))
        d.propertyAmplitude = r.number(in["property_amplitude"], pp + "/property_amplitude").value_or(d.propertyAmplitude);
    if (in.contains("seed")) {
        const auto seed = r.integer(in["seed"], pp + "/seed");
        if (seed && *seed < 0) r.fail(pp + "/seed", "must be >= 0");
        else if (seed) d.seed = uint32_t(*seed);
    }
    if (in.contains("time")) d.time = r.number(in["time"], pp + "/time").value_or(d.time);
}

}  // namespace

core::TranslucentSettings translucentFromJson(const nlohmann::json& j, const std::string& path) {
    JsonReader r;
    core::TranslucentSettings s;
    if (r.object(j, path, {"slice_spacing", "light_buffer", "indirect", "surface_shading", "perturbation"})) {
        if (j.contains("slice_spacing")) s.sliceSpacing = r.number(j["slice_spacing"], path + "/slice_spacing").value_or(s.sliceSpacing);
        if (j.contains("light_buffer")) s.lightBufferSize = r.integer(j["light_buffer"], path + "/light_buffer").value_or(s.lightBufferSize);
        if (j.contains("surface_shading")) s.surfaceShading = r.number(j["surface_shading"], path + "/surface_shading").value_or(s.surfaceShading);
        const std::string ip = path + "/indirect";
        if (j.contains("indirect") && r.object(j["indirect"], ip, {"enabled", "blur_angle_deg", "extinction", "transport_color"})) {
            const auto& in = j["indirect"];
            core::IndirectLight& d = s.indirect;
            if (in.contains("enabled")) d.enabled = r.boolean(in["enabled"], ip + "/enabled").value_or(d.enabled);
            if (in.contains("blur_angle_deg")) d.blurAngleDeg = r.number(in["blur_angle_deg"], ip + "/blur_angle_deg").value_or(d.blurAngleDeg);
            if (in.contains("extinction")) d.extinction = r.number(in["extinction"], ip + "/extinction").value_or(d.extinction);
            if (in.contains("transport_color")) d.transportColor = r.vec3(in["transport_color"], ip + "/transport_color").value_or(d.transportColor);
        }
        if (j.contains("perturbation")) readPerturbation(r, j["perturbation"], path + "/perturbation", s.perturbation);
        for (const auto& p : s.check()) r.check(path, p.field, p.message);
    }
    r.throwIfErrors();
    return s;
}

core::Perturbation perturbationFromJson(const nlohmann::json& j) {
    JsonReader r;
    core::Perturbation p;
    readPerturbation(r, j, "", p);
    for (const auto& problem : p.check()) r.check("", problem.field, problem.message);
    if (r.ok() && !p.active())  // an empty body would commit a copy of the volume as a new version
        r.fail("/amplitude", "amplitude and property_amplitude are both 0: there is nothing to bake");
    r.throwIfErrors();
    return p;
}

core::GlassSphere glassSphereFromJson(const nlohmann::json& j) {
    JsonReader r;
    core::GlassSphere g;
    if (r.object(j, "", {"index", "radius", "edge_voxels", "noise", "noise_frequency", "seed"})) {
        if (j.contains("index")) g.index = r.number(j["index"], "/index").value_or(g.index);
        if (j.contains("radius")) g.radius = r.number(j["radius"], "/radius").value_or(g.radius);
        if (j.contains("edge_voxels")) g.edgeVoxels = r.number(j["edge_voxels"], "/edge_voxels").value_or(g.edgeVoxels);
        if (j.contains("noise")) g.noise = r.number(j["noise"], "/noise").value_or(g.noise);
        if (j.contains("noise_frequency")) g.noiseFrequency = r.number(j["noise_frequency"], "/noise_frequency").value_or(g.noiseFrequency);
        if (j.contains("seed")) {
            const auto seed = r.integer(j["seed"], "/seed");
            if (seed && *seed < 0) r.fail("/seed", "must be >= 0");
            else if (seed) g.seed = uint32_t(*seed);
        }
    }
    if (r.ok())
        for (const auto& [field, message] : g.check()) r.fail("/" + field, message);
    r.throwIfErrors();
    return g;
}

nlohmann::json translucentToJson(const core::TranslucentSettings& s) {
    return {{"slice_spacing", s.sliceSpacing},
            {"light_buffer", s.lightBufferSize},
            {"indirect", {{"enabled", s.indirect.enabled}, {"blur_angle_deg", s.indirect.blurAngleDeg},
                          {"extinction", s.indirect.extinction}, {"transport_color", toJson(s.indirect.transportColor)}}},
            {"surface_shading", s.surfaceShading},
            {"perturbation", {{"amplitude", s.perturbation.amplitude}, {"frequency", s.perturbation.frequency},
                              {"octaves", s.perturbation.octaves}, {"property_amplitude", s.perturbation.propertyAmplitude},
                              {"seed", s.perturbation.seed}, {"time", s.perturbation.time}}}};
}

LightingRequest lightingFromJson(const nlohmann::json& j, const std::string& path, bool allowFilePaths) {
    JsonReader r;
    LightingRequest out;
    core::Lighting& L = out.lighting;
    L.lights.clear();
    std::vector<std::string> lightPaths;  // where each of L.lights came from, for its problems
    if (r.object(j, path, {"sun", "lights", "background", "phase", "environment"})) {
        if (j.contains("sun"))
            if (auto l = lightFromJson(r, j["sun"], path + "/sun")) L.lights.push_back(*l), lightPaths.push_back(path + "/sun");
        if (j.contains("lights")) {
            if (!j["lights"].is_array()) {
                r.fail(path + "/lights", "must be an array of lights");
            } else {
                for (size_t i = 0; i < j["lights"].size(); ++i)
                    if (auto l = lightFromJson(r, j["lights"][i], path + "/lights/" + std::to_string(i)))
                        L.lights.push_back(*l), lightPaths.push_back(path + "/lights/" + std::to_string(i));
            }
        }
        if (j.contains("background")) {
            const auto& b = j["background"];
            const std::string bp = path + "/background";
            if (b.is_array()) {
                L.background.color = r.vec3(b, bp).value_or(L.background.color);
            } else if (r.object(b, bp, {"color", "environment"})) {
                if (b.contains("color")) L.background.color = r.vec3(b["color"], bp + "/color").value_or(L.background.color);
                if (b.contains("environment")) {
                    const std::optional<std::string> map = r.string(b["environment"], bp + "/environment");
                    if (map == kLobesBackground) L.background.fromLobes = true;  // the environment light, seen
                    else if (allowFilePaths) out.environmentPath = map;
                    else if (map == kSessionMap) out.backgroundUsesSessionMap = true;
                    else if (map) r.fail(bp + "/environment", "file paths are not accepted here; upload the map (PUT /sessions/{sid}/environment) and give \"session\"");
                }
            }
        }
        if (j.contains("phase") && r.object(j["phase"], path + "/phase", {"type", "g"})) {
            const auto& ph = j["phase"];
            std::string type = ph.contains("type") ? r.string(ph["type"], path + "/phase/type").value_or("") : "isotropic";
            if (type == "isotropic") {
                L.phase.type = core::PhaseType::Isotropic;
            } else if (type == "henyey_greenstein") {
                L.phase.type = core::PhaseType::HenyeyGreenstein;
            } else if (!type.empty()) {
                r.fail(path + "/phase/type", "must be 'isotropic' or 'henyey_greenstein', got '" + type + "'");
            }
            if (ph.contains("g")) L.phase.g = r.number(ph["g"], path + "/phase/g").value_or(0);
        }
        if (j.contains("environment")) environmentFromJson(r, j["environment"], path + "/environment", allowFilePaths, out);
        // Every problem at once: values that parsed are checked even when others did not (those
        // keep valid defaults), each under the field it came from ("sun" is not "lights/0").
        for (const auto& problem : L.check()) {
            size_t light = 0, used = 0;
            if (std::sscanf(problem.field.c_str(), "lights/%zu%zn", &light, &used) == 1 && light < lightPaths.size())
                r.check(lightPaths[light], problem.field.substr(size_t(used) + 1), problem.message);
            else
                r.check(path, problem.field, problem.message);
        }
    }
    r.throwIfErrors();
    return out;
}

core::Lighting LightingRequest::resolve(const std::shared_ptr<const core::Image>& sessionMap, const std::string& path) const {
    core::Lighting L = lighting;
    if (!usesSessionMap()) return L;
    JsonReader r;
    const std::string missing = "names the session's environment map, but none is uploaded (PUT /sessions/{sid}/environment)";
    if (backgroundUsesSessionMap) {
        if (sessionMap) L.background.environment = sessionMap;
        else r.fail(path + "/background/environment", missing);
    }
    if (environmentUsesSessionMap) {
        if (sessionMap) L.environment.map = sessionMap, L.environment.radiance.clear();
        else r.fail(path + "/environment/map", missing);
    }
    r.throwIfErrors();
    return L;
}

nlohmann::json lightingToJson(const core::Lighting& L, const core::Image* sessionMap) {
    nlohmann::json j;
    if (L.lights.size() == 1) {
        j["sun"] = {{"direction", toJson(L.lights[0].direction)}, {"irradiance", toJson(L.lights[0].irradiance)}};
    } else if (!L.lights.empty()) {
        j["lights"] = nlohmann::json::array();
        for (const auto& l : L.lights)
            j["lights"].push_back({{"direction", toJson(l.direction)}, {"irradiance", toJson(l.irradiance)}});
    }
    const bool sessionBackground = sessionMap && L.background.environment.get() == sessionMap;
    if (sessionBackground || L.background.fromLobes)
        j["background"] = {{"color", toJson(L.background.color)}, {"environment", L.background.fromLobes ? kLobesBackground : kSessionMap}};
    else
        j["background"] = toJson(L.background.color);
    j["phase"] = L.phase.type == core::PhaseType::Isotropic
                     ? nlohmann::json{{"type", "isotropic"}}
                     : nlohmann::json{{"type", "henyey_greenstein"}, {"g", L.phase.g}};
    if (L.environment.active()) {
        const core::EnvironmentLight& e = L.environment;
        nlohmann::json radiance = nlohmann::json::array();
        // The radiances as the volume sees them (a map's projection included), strength 1.
        core::EnvironmentLight unscaled = e;
        unscaled.strength = 1;
        for (const Vec3d& c : core::lobeRadiance(unscaled)) radiance.push_back(toJson(c));
        j["environment"] = {{"lobes", e.lobes},
                            {"domain", e.domain == core::LobeDomain::Sphere ? "sphere" : "upper_hemisphere"},
                            {"radiance", radiance},
                            {"strength", e.strength},
                            {"light_volume_resolution", e.lightVolumeResolution}};
        if (sessionMap && e.map.get() == sessionMap) j["environment"]["map"] = kSessionMap;  // radiance: its projection
    }
    return j;
}

}  // namespace volstyle::protocol
