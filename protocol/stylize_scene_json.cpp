// The stylizer's scene as JSON (SPEC §7): occluders, light, medium, camera, transfer function,
// key frames and the heterogeneous medium, read (types here; every range from the core value's
// one check()) and written.
#include "protocol/stylize_json.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "protocol/render_json.h"

namespace volstyle::protocol {

std::shared_ptr<const core::Mesh> builtinMesh(const std::string& ref) {
    static const core::StylizerScene forest = core::builtinForest();
    if (ref.rfind(kBuiltinMeshPrefix, 0) != 0) return nullptr;
    for (const core::Occluder& o : forest.occluders)
        if (kBuiltinMeshPrefix + o.name == ref) return o.mesh;
    return nullptr;
}
namespace {


/// A column-major 4x4 affine matrix (OpenGL's and glTF's order).
std::optional<Mat4> transformFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path) {
    if (!j.is_array() || j.size() != 16) {
        r.fail(path, "must be 16 numbers (a column-major 4x4 matrix)");
        return std::nullopt;
    }
    Mat4 m;
    bool ok = true;
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) {
            const std::string at = path + "/" + std::to_string(4 * c + row);
            auto v = r.number(j[size_t(4 * c + row)], at);
            if (v && !(std::abs(*v) <= 1e9)) r.fail(at, "must be within ±1e9 (larger scales overflow the renderer's floats)"), v.reset();
            if (v) m(row, c) = *v;
            else ok = false;
        }
    if (!ok) return std::nullopt;
    if (!m.isAffine()) {
        r.fail(path, "must be affine (its last row 0, 0, 0, 1)");
        return std::nullopt;
    }
    try {
        (void)m.inverseAffine();
    } catch (const InvalidArgument&) {
        r.fail(path, "is singular");
        return std::nullopt;
    }
    return m;
}


/// {"closing": {"radius_px": 4, "shape": "disc"|"box"}, "dilation": {"length": 0.3, "erosion_px": 2},
///  "holes": {"frequency": 0.3, "probability": 0.4, "seed": 1, "speed": 0, "octaves": 5, "persistence": 0.5}}
core::Manipulation manipulationFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path) {
    core::Manipulation m;
    if (!r.object(j, path, {"closing", "dilation", "holes"})) return m;
    // Types here; ranges in core::Manipulation::check() alone (reported below, with their paths).
    if (j.contains("closing") && r.object(j["closing"], path + "/closing", {"radius_px", "shape"})) {
        const auto& c = j["closing"];
        if (!c.contains("radius_px")) r.fail(path + "/closing/radius_px", "is required");
        else m.closingRadius = r.integer(c["radius_px"], path + "/closing/radius_px").value_or(0);
        const std::string shape = c.contains("shape") ? r.string(c["shape"], path + "/closing/shape").value_or("disc") : "disc";
        if (shape == "box") m.closingShape = core::MorphShape::Box;
        else if (shape != "disc") r.fail(path + "/closing/shape", "must be 'disc' or 'box', got '" + shape + "'");
    }
    const std::string dp = path + "/dilation";
    if (j.contains("dilation") && r.object(j["dilation"], dp, {"length", "erosion_px"})) {
        const auto& d = j["dilation"];
        if (!d.contains("length")) r.fail(dp + "/length", "is required (world units)");
        else m.dilationLength = r.number(d["length"], dp + "/length").value_or(0);
        if (d.contains("erosion_px")) m.erosionPx = r.integer(d["erosion_px"], dp + "/erosion_px").value_or(0);
    }
    const std::string hp = path + "/holes";
    if (j.contains("holes") && r.object(j["holes"], hp, {"frequency", "probability", "seed", "speed", "octaves", "persistence"})) {
        const auto& h = j["holes"];
        if (!h.contains("probability")) r.fail(hp + "/probability", "is required (the share of the shadow that becomes holes)");
        else m.holeProbability = r.number(h["probability"], hp + "/probability").value_or(0);
        if (h.contains("frequency")) m.holeFrequency = r.number(h["frequency"], hp + "/frequency").value_or(m.holeFrequency);
        if (h.contains("seed")) m.holeSeed = uint32_t(boundedNumber(r, h["seed"], hp + "/seed", 0, 4294967295.0, 1));
        if (h.contains("seed") && !h["seed"].is_number_integer() && !h["seed"].is_number_unsigned()) r.fail(hp + "/seed", "must be an integer");
        if (h.contains("speed")) m.holeSpeed = r.number(h["speed"], hp + "/speed").value_or(0);
        if (h.contains("octaves")) m.holeOctaves = r.integer(h["octaves"], hp + "/octaves").value_or(m.holeOctaves);
        if (h.contains("persistence")) m.holePersistence = r.number(h["persistence"], hp + "/persistence").value_or(m.holePersistence);
    }
    for (const core::FieldProblem& p : m.check()) {
        const auto slash = p.field.rfind('/');
        r.check(path + "/" + p.field.substr(0, slash), p.field.substr(slash + 1), p.message);  // not where the type already failed
    }
    return m;
}

void phaseFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, core::Phase& phase) {
    if (!r.object(j, path, {"type", "g"})) return;
    const std::string type = j.contains("type") ? r.string(j["type"], path + "/type").value_or("") : "isotropic";
    if (type == "isotropic") phase.type = core::PhaseType::Isotropic;
    else if (type == "henyey_greenstein") phase.type = core::PhaseType::HenyeyGreenstein;
    else if (!type.empty()) r.fail(path + "/type", "must be 'isotropic' or 'henyey_greenstein', got '" + type + "'");
    if (j.contains("g")) {
        if (auto g = r.number(j["g"], path + "/g")) {
            if (!(*g > -1 && *g < 1)) r.fail(path + "/g", "must be in (-1, 1)");
            else phase.g = *g;
        }
    }
}

}  // namespace

core::StylizerVolume volumeFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, SceneSource source,
                                    StylizerSceneRequest& out) {
    core::StylizerVolume v;
    if (!r.object(j, path, {"source", "box", "extinction_scale", "light_transmittance", "steps"})) return v;
    out.volumeSource = j.contains("source") ? r.string(j["source"], path + "/source").value_or("") : (source == SceneSource::Api ? "session" : "");
    if (source == SceneSource::Api && out.volumeSource != "session")
        r.fail(path + "/source", "the API's stylizer uses the session's volume: \"session\" (upload another with PUT …/volume)");
    if (source == SceneSource::File && out.volumeSource.empty()) r.fail(path + "/source", "is required: a VDB file or builtin:NAME");
    if (j.contains("box")) {
        const auto& b = j["box"];
        std::optional<Vec3d> lo, hi;
        if (b.is_array() && b.size() == 2) lo = r.vec3(b[0], path + "/box/0"), hi = r.vec3(b[1], path + "/box/1");
        else r.fail(path + "/box", "must be [[x0, y0, z0], [x1, y1, z1]]");
        if (lo && hi) {
            if (hi->x > lo->x && hi->y > lo->y && hi->z > lo->z && std::abs(lo->x) <= 1e9 && std::abs(lo->y) <= 1e9 && std::abs(lo->z) <= 1e9 &&
                std::abs(hi->x) <= 1e9 && std::abs(hi->y) <= 1e9 && std::abs(hi->z) <= 1e9)
                v.lo = *lo, v.hi = *hi, out.volumeBoxGiven = true;
            else r.fail(path + "/box", "the second corner must be above the first on every axis (finite, |x| <= 1e9)");
        }
    }
    if (j.contains("extinction_scale")) v.extinctionScale = boundedNumber(r, j["extinction_scale"], path + "/extinction_scale", 0, 1e6, 1);
    if (j.contains("light_transmittance")) v.lightTransmittance = r.boolean(j["light_transmittance"], path + "/light_transmittance").value_or(true);
    if (j.contains("steps")) {
        v.steps = r.integer(j["steps"], path + "/steps").value_or(v.steps);
        if (v.steps < 1 || v.steps > 4096) r.check(path, "steps", "must be in [1, 4096]");
    }
    return v;
}

namespace {

/// Reports a core value's check() problems under `path` (not where a field already failed to read).
void reportProblems(JsonReader& r, const std::string& path, const std::vector<core::FieldProblem>& problems) {
    for (const core::FieldProblem& p : problems) r.check(path, p.field, p.message);
}

/// A camera at `path`, its problems recorded in `r`.
core::Camera readCameraInto(JsonReader& r, const nlohmann::json& j, const std::string& path, const core::Camera& fallback) {
    try {
        return cameraFromJson(j, path);
    } catch (const ValidationError& e) {
        for (const FieldError& f : e.details()) r.fail(f.path, f.message);
        return fallback;
    }
}

/// "keyframes": [{"time", "camera", "transfer_function"?}, …] by increasing time.
void keyframesFromJson(JsonReader& r, const nlohmann::json& list, const std::string& path, SceneSource source, StylizerSceneRequest& out) {
    if (!list.is_array()) return r.fail(path, "must be an array of keys");
    if (list.size() > core::kMaxKeyframes) return r.fail(path, "at most " + std::to_string(core::kMaxKeyframes) + " keys");
    auto& keys = out.scene.keyframes;
    for (size_t i = 0; i < list.size(); ++i) {
        const std::string kp = path + "/" + std::to_string(i);
        core::StylizerKeyframe key;
        if (r.object(list[i], kp, {"time", "camera", "transfer_function"})) {
            const auto& k = list[i];
            if (!k.contains("time")) r.fail(kp + "/time", "is required");
            else key.time = boundedNumber(r, k["time"], kp + "/time", -1e9, 1e9, 0);
            if (!k.contains("camera")) r.fail(kp + "/camera", "is required");
            else key.camera = readCameraInto(r, k["camera"], kp + "/camera", key.camera);
            if (k.contains("transfer_function")) {
                std::vector<TfImageRef> refs;
                key.transferFunction = transferFunctionFromJson(r, k["transfer_function"], kp + "/transfer_function", source, refs);
                for (TfImageRef& ref : refs) ref.key = int(i), out.tfImages.push_back(ref);
            }
        }
        if (i > 0 && !(key.time > keys.back().time) && !r.failed(kp + "/time")) r.fail(kp + "/time", "keys go by increasing time");
        keys.push_back(std::move(key));
    }
}

/// One occluder: {"name"?, "mesh", "transform"?, "colour"?, "manipulation"?}; its mesh reference
/// goes to out.meshRefs.
void occluderFromJson(JsonReader& r, const nlohmann::json& j, const std::string& op, size_t i, StylizerSceneRequest& out) {
    if (!r.object(j, op, {"name", "mesh", "transform", "colour", "manipulation"})) return;
    core::Occluder o;
    if (j.contains("manipulation")) o.manipulation = manipulationFromJson(r, j["manipulation"], op + "/manipulation");
    o.name = j.contains("name") ? r.string(j["name"], op + "/name").value_or("") : "occluder" + std::to_string(i);
    if (j.contains("name") && o.name.empty()) r.fail(op + "/name", "must not be empty");
    const auto& others = out.scene.occluders;
    for (size_t k = 0; k < others.size(); ++k)
        if (!o.name.empty() && others[k].name == o.name)
            r.fail(op + "/name", "'" + o.name + "' already names occluder " + std::to_string(k) + "; names are unique");
    std::string mesh;
    if (!j.contains("mesh")) r.fail(op + "/mesh", "is required");
    else mesh = r.string(j["mesh"], op + "/mesh").value_or("");
    if (j.contains("transform")) o.worldFromObject = transformFromJson(r, j["transform"], op + "/transform").value_or(Mat4::identity());
    if (j.contains("colour")) {
        o.colour = r.vec3(j["colour"], op + "/colour").value_or(o.colour);
        for (int c = 0; c < 3; ++c)
            if (!(o.colour[c] >= 0 && o.colour[c] <= 1)) r.check(op, "colour", "must be in [0, 1]");
    }
    out.scene.occluders.push_back(std::move(o));
    out.meshRefs.push_back(mesh);
}

/// "light": {"type", "direction", "position", "cone_deg", "irradiance", "shadow_map_size"}; the
/// ranges are StylizerLight::check()'s.
void lightFromJson(JsonReader& r, const nlohmann::json& l, const std::string& lp, core::StylizerLight& light) {
    if (!r.object(l, lp, {"type", "direction", "position", "cone_deg", "irradiance", "shadow_map_size"})) return;
    const std::string type = l.contains("type") ? r.string(l["type"], lp + "/type").value_or("") : "directional";
    if (type == "spot") light.type = core::StylizerLightType::Spot;
    else if (type != "directional" && !type.empty()) r.fail(lp + "/type", "must be 'directional' or 'spot', got '" + type + "'");
    if (l.contains("direction")) light.direction = r.vec3(l["direction"], lp + "/direction").value_or(light.direction);
    if (light.type == core::StylizerLightType::Spot) {
        if (!l.contains("position")) r.fail(lp + "/position", "is required for a spot light");
        else light.position = r.vec3(l["position"], lp + "/position").value_or(light.position);
        if (l.contains("cone_deg")) light.coneDeg = r.number(l["cone_deg"], lp + "/cone_deg").value_or(light.coneDeg);
    } else {
        // A directional light has no use for them: a typo for "spot" should not pass unseen.
        for (const char* field : {"position", "cone_deg"})
            if (l.contains(field)) r.fail(lp + "/" + field, "is for spot lights; set \"type\": \"spot\" or remove it");
    }
    if (l.contains("irradiance")) light.irradiance = r.vec3(l["irradiance"], lp + "/irradiance").value_or(light.irradiance);
    if (l.contains("shadow_map_size")) light.shadowMapSize = r.integer(l["shadow_map_size"], lp + "/shadow_map_size").value_or(light.shadowMapSize);
    reportProblems(r, lp, light.check());
}

/// "medium": {"extinction", "albedo", "phase"}; the ranges are HomogeneousMedium::check()'s.
void mediumFromJson(JsonReader& r, const nlohmann::json& m, const std::string& mp, core::HomogeneousMedium& medium) {
    if (!r.object(m, mp, {"extinction", "albedo", "phase"})) return;
    if (m.contains("extinction")) medium.extinction = r.number(m["extinction"], mp + "/extinction").value_or(medium.extinction);
    if (m.contains("albedo")) medium.albedo = r.number(m["albedo"], mp + "/albedo").value_or(medium.albedo);
    if (m.contains("phase")) phaseFromJson(r, m["phase"], mp + "/phase", medium.phase);
    reportProblems(r, mp, medium.check());
}

}  // namespace

StylizerSceneRequest stylizerSceneFromJson(const nlohmann::json& j, const std::string& path, SceneSource source) {
    JsonReader r;
    StylizerSceneRequest out;
    core::StylizerScene& s = out.scene;
    if (r.object(j, path, {"occluders", "light", "medium", "camera", "background", "time", "transfer_function", "keyframes", "volume"})) {
        if (j.contains("transfer_function"))
            s.transferFunction = transferFunctionFromJson(r, j["transfer_function"], path + "/transfer_function", source, out.tfImages);
        if (j.contains("keyframes")) keyframesFromJson(r, j["keyframes"], path + "/keyframes", source, out);
        if (j.contains("volume")) s.volume = volumeFromJson(r, j["volume"], path + "/volume", source, out);
        if (j.contains("occluders")) {
            const auto& list = j["occluders"];
            if (!list.is_array()) r.fail(path + "/occluders", "must be an array of occluders");
            else
                for (size_t i = 0; i < list.size(); ++i) occluderFromJson(r, list[i], path + "/occluders/" + std::to_string(i), i, out);
        }
        if (j.contains("light")) lightFromJson(r, j["light"], path + "/light", s.light);
        if (j.contains("medium")) mediumFromJson(r, j["medium"], path + "/medium", s.medium);
        if (j.contains("camera")) s.camera = readCameraInto(r, j["camera"], path + "/camera", s.camera);
        if (j.contains("background")) {
            s.background = r.vec3(j["background"], path + "/background").value_or(s.background);
            for (int c = 0; c < 3; ++c)
                if (!(s.background[c] >= 0 && s.background[c] <= 1e6)) {
                    r.check(path, "background", "must be in [0, 1e6]");
                    break;
                }
        }
        if (j.contains("time")) s.time = boundedNumber(r, j["time"], path + "/time", -1e9, 1e9, 0);
    }
    r.throwIfErrors();
    return out;
}

namespace {

nlohmann::json vec3Json(const Vec3d& v) { return {v.x, v.y, v.z}; }

nlohmann::json manipulationToJson(const core::Manipulation& m) {
    nlohmann::json j = nlohmann::json::object();
    if (m.closingRadius > 0)
        j["closing"] = {{"radius_px", m.closingRadius}, {"shape", m.closingShape == core::MorphShape::Box ? "box" : "disc"}};
    if (m.dilationLength > 0) j["dilation"] = {{"length", m.dilationLength}, {"erosion_px", m.erosionPx}};
    if (m.holeProbability > 0)
        j["holes"] = {{"frequency", m.holeFrequency}, {"probability", m.holeProbability}, {"seed", m.holeSeed},
                      {"speed", m.holeSpeed}, {"octaves", m.holeOctaves}, {"persistence", m.holePersistence}};
    return j;
}

}  // namespace

nlohmann::json stylizerSceneToJson(const core::StylizerScene& scene, const std::vector<std::string>& meshRefs,
                                   const std::optional<std::string>& transferImageRef, const std::string& volumeSource) {
    nlohmann::json occluders = nlohmann::json::array();
    for (size_t i = 0; i < scene.occluders.size(); ++i) {
        const core::Occluder& o = scene.occluders[i];
        nlohmann::json transform = nlohmann::json::array();
        for (int c = 0; c < 4; ++c)
            for (int row = 0; row < 4; ++row) transform.push_back(o.worldFromObject(row, c));
        occluders.push_back({{"name", o.name}, {"mesh", i < meshRefs.size() ? meshRefs[i] : ""}, {"transform", transform},
                             {"colour", vec3Json(o.colour)}, {"manipulation", manipulationToJson(o.manipulation)}});
    }
    const core::StylizerLight& l = scene.light;
    nlohmann::json light = {{"type", l.type == core::StylizerLightType::Spot ? "spot" : "directional"},
                            {"direction", vec3Json(l.direction)}, {"irradiance", vec3Json(l.irradiance)},
                            {"shadow_map_size", l.shadowMapSize}};
    if (l.type == core::StylizerLightType::Spot) light["position"] = vec3Json(l.position), light["cone_deg"] = l.coneDeg;
    const core::Phase& phase = scene.medium.phase;
    nlohmann::json phaseJson = {{"type", phase.type == core::PhaseType::HenyeyGreenstein ? "henyey_greenstein" : "isotropic"}};
    if (phase.type == core::PhaseType::HenyeyGreenstein) phaseJson["g"] = phase.g;
    nlohmann::json j = {{"occluders", occluders},
                        {"light", light},
                        {"medium", {{"extinction", scene.medium.extinction}, {"albedo", scene.medium.albedo}, {"phase", phaseJson}}},
                        {"camera", cameraToJson(scene.camera)},
                        {"background", vec3Json(scene.background)},
                        {"time", scene.time}};
    if (const auto& tf = scene.transferFunction) j["transfer_function"] = transferFunctionToJson(*tf, transferImageRef);
    if (const auto& v = scene.volume)
        j["volume"] = {{"source", volumeSource.empty() ? "session" : volumeSource},
                       {"box", {vec3Json(v->lo), vec3Json(v->hi)}},
                       {"extinction_scale", v->extinctionScale},
                       {"light_transmittance", v->lightTransmittance},
                       {"steps", v->steps}};
    if (!scene.keyframes.empty()) {
        nlohmann::json keys = nlohmann::json::array();
        for (const core::StylizerKeyframe& k : scene.keyframes) {
            keys.push_back({{"time", k.time}, {"camera", cameraToJson(k.camera)}});
            if (k.transferFunction) keys.back()["transfer_function"] = transferFunctionToJson(*k.transferFunction);
        }
        j["keyframes"] = keys;
    }
    return j;
}

}  // namespace volstyle::protocol
