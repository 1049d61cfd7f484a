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

/// A number at `path` within [lo, hi], or `fallback` (a failure is recorded).
double boundedNumber(JsonReader& r, const nlohmann::json& j, const std::string& path, double lo, double hi, double fallback) {
    auto v = r.number(j, path);
    if (!v) return fallback;
    if (!(*v >= lo && *v <= hi)) {
        // Whole bounds print as integers ("[0, 150]", not "[0.0, 150.0]").
        auto text = [](double v) { return v == std::floor(v) && std::abs(v) < 1e15 ? std::to_string(static_cast<long long>(v)) : nlohmann::json(v).dump(); };
        r.fail(path, "must be in [" + text(lo) + ", " + text(hi) + "]");
        return fallback;
    }
    return *v;
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

StylizerSceneRequest stylizerSceneFromJson(const nlohmann::json& j, const std::string& path, SceneSource source) {
    JsonReader r;
    StylizerSceneRequest out;
    core::StylizerScene& s = out.scene;
    if (r.object(j, path, {"occluders", "light", "medium", "camera", "background", "time", "transfer_function", "keyframes", "volume"})) {
        if (j.contains("transfer_function"))
            s.transferFunction = transferFunctionFromJson(r, j["transfer_function"], path + "/transfer_function", source, out.tfImages);
        if (j.contains("keyframes")) {
            const auto& list = j["keyframes"];
            if (!list.is_array()) r.fail(path + "/keyframes", "must be an array of keys");
            else if (list.size() > core::kMaxKeyframes) r.fail(path + "/keyframes", "at most " + std::to_string(core::kMaxKeyframes) + " keys");
            else
                for (size_t i = 0; i < list.size(); ++i) {
                    const std::string kp = path + "/keyframes/" + std::to_string(i);
                    core::StylizerKeyframe key;
                    if (r.object(list[i], kp, {"time", "camera", "transfer_function"})) {
                        const auto& k = list[i];
                        if (!k.contains("time")) r.fail(kp + "/time", "is required");
                        else key.time = boundedNumber(r, k["time"], kp + "/time", -1e9, 1e9, 0);
                        if (!k.contains("camera")) r.fail(kp + "/camera", "is required");
                        else try {
                                key.camera = cameraFromJson(k["camera"], kp + "/camera");
                            } catch (const ValidationError& e) {
                                for (const FieldError& f : e.details()) r.fail(f.path, f.message);
                            }
                        if (k.contains("transfer_function")) {
                            std::vector<TfImageRef> refs;
                            key.transferFunction = transferFunctionFromJson(r, k["transfer_function"], kp + "/transfer_function", source, refs);
                            for (TfImageRef& ref : refs) ref.key = int(i), out.tfImages.push_back(ref);
                        }
                    }
                    if (i > 0 && !(key.time > s.keyframes.back().time) && !r.failed(kp + "/time"))
                        r.fail(kp + "/time", "keys go by increasing time");
                    s.keyframes.push_back(std::move(key));
                }
        }
        if (j.contains("volume")) s.volume = volumeFromJson(r, j["volume"], path + "/volume", source, out);
        if (j.contains("occluders")) {
            const auto& list = j["occluders"];
            if (!list.is_array()) r.fail(path + "/occluders", "must be an array of occluders");
            else
                for (size_t i = 0; i < list.size(); ++i) {
                    const std::string op = path + "/occluders/" + std::to_string(i);
                    if (!r.object(list[i], op, {"name", "mesh", "transform", "colour", "manipulation"})) continue;
                    core::Occluder o;
                    if (list[i].contains("manipulation")) o.manipulation = manipulationFromJson(r, list[i]["manipulation"], op + "/manipulation");
                    o.name = list[i].contains("name") ? r.string(list[i]["name"], op + "/name").value_or("") : "occluder" + std::to_string(i);
                    if (list[i].contains("name") && o.name.empty()) r.fail(op + "/name", "must not be empty");
                    for (size_t k = 0; k < s.occluders.size(); ++k)
                        if (!o.name.empty() && s.occluders[k].name == o.name)
                            r.fail(op + "/name", "'" + o.name + "' already names occluder " + std::to_string(k) + "; names are unique");
                    std::string mesh;
                    if (!list[i].contains("mesh")) r.fail(op + "/mesh", "is required");
                    else mesh = r.string(list[i]["mesh"], op + "/mesh").value_or("");
                    if (list[i].contains("transform"))
                        o.worldFromObject = transformFromJson(r, list[i]["transform"], op + "/transform").value_or(Mat4::identity());
                    if (list[i].contains("colour")) {
                        o.colour = r.vec3(list[i]["colour"], op + "/colour").value_or(o.colour);
                        for (int c = 0; c < 3; ++c)
                            if (!(o.colour[c] >= 0 && o.colour[c] <= 1)) r.check(op, "colour", "must be in [0, 1]");
                    }
                    s.occluders.push_back(std::move(o));
                    out.meshRefs.push_back(mesh);
                }
        }
        if (j.contains("light")) {
            const auto& l = j["light"];
            const std::string lp = path + "/light";
            if (r.object(l, lp, {"type", "direction", "position", "cone_deg", "irradiance", "shadow_map_size"})) {
                const std::string type = l.contains("type") ? r.string(l["type"], lp + "/type").value_or("") : "directional";
                if (type == "spot") s.light.type = core::StylizerLightType::Spot;
                else if (type != "directional" && !type.empty()) r.fail(lp + "/type", "must be 'directional' or 'spot', got '" + type + "'");
                if (l.contains("direction")) s.light.direction = r.vec3(l["direction"], lp + "/direction").value_or(s.light.direction);
                if (s.light.type == core::StylizerLightType::Spot) {
                    if (!l.contains("position")) r.fail(lp + "/position", "is required for a spot light");
                    else s.light.position = r.vec3(l["position"], lp + "/position").value_or(s.light.position);
                    for (int k = 0; k < 3; ++k)
                        if (!(std::abs(s.light.position[k]) <= 1e9)) {
                            r.check(lp, "position", "must be finite (|x| <= 1e9)");
                            break;
                        }
                    if (l.contains("cone_deg")) s.light.coneDeg = boundedNumber(r, l["cone_deg"], lp + "/cone_deg", 0, 150, s.light.coneDeg);
                    if (!(s.light.coneDeg > 0)) r.check(lp, "cone_deg", "must be in (0, 150]");
                } else {
                    // A directional light has no use for them: a typo for "spot" should not pass unseen.
                    for (const char* field : {"position", "cone_deg"})
                        if (l.contains(field)) r.fail(lp + "/" + field, "is for spot lights; set \"type\": \"spot\" or remove it");
                }
                if (l.contains("irradiance")) s.light.irradiance = r.vec3(l["irradiance"], lp + "/irradiance").value_or(s.light.irradiance);
                if (l.contains("shadow_map_size"))
                    s.light.shadowMapSize = r.integer(l["shadow_map_size"], lp + "/shadow_map_size").value_or(s.light.shadowMapSize);
                const Vec3d& d = s.light.direction;
                if (!(std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}) <= 1e9)) r.check(lp, "direction", "must be within ±1e9 (only its direction counts)");
                else if (!(length(d) > 0)) r.check(lp, "direction", "must not be zero");
                if (s.light.shadowMapSize < 512 || s.light.shadowMapSize > 4096) r.check(lp, "shadow_map_size", "must be in [512, 4096]");
                bool irradianceOk = true;
                for (int c = 0; c < 3; ++c) irradianceOk = irradianceOk && s.light.irradiance[c] >= 0 && s.light.irradiance[c] <= 1e6;
                if (!irradianceOk) r.check(lp, "irradiance", "must be in [0, 1e6]");
            }
        }
        if (j.contains("medium")) {
            const auto& m = j["medium"];
            const std::string mp = path + "/medium";
            if (r.object(m, mp, {"extinction", "albedo", "phase"})) {
                if (m.contains("extinction")) s.medium.extinction = r.number(m["extinction"], mp + "/extinction").value_or(s.medium.extinction);
                if (m.contains("albedo")) s.medium.albedo = r.number(m["albedo"], mp + "/albedo").value_or(s.medium.albedo);
                if (m.contains("phase")) phaseFromJson(r, m["phase"], mp + "/phase", s.medium.phase);
                if (!(s.medium.extinction >= 0 && s.medium.extinction <= 1e6)) r.check(mp, "extinction", "must be in [0, 1e6]");
                if (!(s.medium.albedo >= 0 && s.medium.albedo <= 1)) r.check(mp, "albedo", "must be in [0, 1]");
            }
        }
        if (j.contains("camera")) {
            try {
                s.camera = cameraFromJson(j["camera"], path + "/camera");
            } catch (const ValidationError& e) {
                for (const FieldError& f : e.details()) r.fail(f.path, f.message);
            }
        }
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

void attachTfImage(core::StylizerScene& scene, const TfImageRef& ref, std::shared_ptr<const core::Image> image) {
    core::TransferFunction& tf = ref.key < 0 ? *scene.transferFunction : *scene.keyframes.at(size_t(ref.key)).transferFunction;
    if (ref.layer < 0) tf.image = std::move(image);
    else tf.layers.at(size_t(ref.layer)).image = std::move(image);
}

const char* const kStylizerAovNames = "average_visibility, linear_depth, shadow_map, modified_shadow_map, scattering";

std::optional<core::StylizerOutput> stylizerOutputFromName(const std::string& name) {
    using O = core::StylizerOutput;
    static const std::map<std::string, O> names = {{"frame", O::Frame},
                                                   {"average_visibility", O::AverageVisibility},
                                                   {"linear_depth", O::LinearDepth},
                                                   {"shadow_map", O::ShadowMap},
                                                   {"modified_shadow_map", O::ModifiedShadowMap},
                                                   {"scattering", O::Scattering}};
    auto it = names.find(name);
    if (it == names.end()) return std::nullopt;
    return it->second;
}

namespace {

/// "aov", "exposure", "method" and "steps" of a frame or sequence request.
void readFrameOptions(JsonReader& r, const nlohmann::json& j, core::StylizerOutput& output, core::StylizeSettings& settings, double& exposure) {
    if (j.contains("aov")) {
        if (auto name = r.string(j["aov"], "/aov")) {
            if (auto o = stylizerOutputFromName(*name)) output = *o;
            else r.fail("/aov", "must be one of frame, " + std::string(kStylizerAovNames) + "; got '" + *name + "'");
        }
    }
    if (j.contains("exposure")) {
        exposure = r.number(j["exposure"], "/exposure").value_or(0);
        if (auto why = exposureProblem(exposure); !why.empty()) r.fail("/exposure", why), exposure = 0;
    }
    if (j.contains("method")) {
        auto m = r.string(j["method"], "/method");
        if (m == "naive") settings.method = core::VisibilityMethod::Naive;
        else if (m && *m != "accelerated") r.fail("/method", "must be 'accelerated' or 'naive', got '" + *m + "'");
    }
    if (j.contains("steps")) {
        settings.steps = r.integer(j["steps"], "/steps").value_or(settings.steps);
        if (settings.steps < 1 || settings.steps > 4096) r.check("", "steps", "must be in [1, 4096]");
    }
}

}  // namespace

StylizerFrameRequest StylizerFrameRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits) {
    JsonReader r;
    StylizerFrameRequest q;
    if (r.object(j, "", {"camera", "format", "aov", "time", "method", "steps", "exposure"})) {
        if (j.contains("camera")) q.camera = readCamera(r, j, "/camera", limits);
        if (j.contains("format")) {
            auto f = r.string(j["format"], "/format");
            if (f == "png") q.format = ImageFormat::Png;
            else if (f == "jpeg" || f == "jpg") q.format = ImageFormat::Jpeg;
            else if (f == "exr") q.format = ImageFormat::Exr;
            else if (f) r.fail("/format", "must be 'png', 'jpeg' or 'exr', got '" + *f + "'");
        }
        if (j.contains("time")) q.time = boundedNumber(r, j["time"], "/time", -1e9, 1e9, 0);
        readFrameOptions(r, j, q.output, q.settings, q.exposure);
    }
    r.throwIfErrors();
    return q;
}

StylizerPickRequest StylizerPickRequest::fromJson(const nlohmann::json& j, const RequestLimits& limits, bool constraint) {
    JsonReader r;
    StylizerPickRequest q;
    const bool ok = constraint ? r.object(j, "", {"x", "y", "camera", "time", "colour", "alpha", "layer", "anchor"})
                               : r.object(j, "", {"x", "y", "camera", "time"});
    if (ok) {
        for (auto [field, into] : {std::pair{"x", &q.x}, std::pair{"y", &q.y}}) {
            if (!j.contains(field)) r.fail(std::string("/") + field, "is required (the pixel, 0 at the top left)");
            else *into = r.integer(j[field], std::string("/") + field).value_or(0);
        }
        if (j.contains("camera")) q.camera = readCamera(r, j, "/camera", limits);
        if (j.contains("time")) q.time = boundedNumber(r, j["time"], "/time", -1e9, 1e9, 0);
        if (j.contains("colour")) {
            if (auto c = r.vec3(j["colour"], "/colour")) {
                if (c->x >= 0 && c->x <= 1 && c->y >= 0 && c->y <= 1 && c->z >= 0 && c->z <= 1) q.colour = *c;
                else r.fail("/colour", "each component must be in [0, 1] (linear)");
            }
        }
        if (j.contains("alpha")) q.alpha = boundedNumber(r, j["alpha"], "/alpha", 0, 1, 1);
        if (j.contains("layer")) q.layer = r.integer(j["layer"], "/layer");
        if (j.contains("anchor")) {
            const auto a = r.string(j["anchor"], "/anchor");
            if (a == "world") q.anchor = Anchor::World;
            else if (a == "object") q.anchor = Anchor::Object;
            else if (a && *a != "none") r.fail("/anchor", "must be 'none', 'world' or 'object', got '" + *a + "'");
        }
    }
    r.throwIfErrors();
    return q;
}

StylizerSequenceRequest StylizerSequenceRequest::fromJson(const nlohmann::json& j) {
    JsonReader r;
    StylizerSequenceRequest q;
    if (r.object(j, "", {"fps", "start", "end", "video", "aov", "exposure", "method", "steps"})) {
        if (j.contains("fps")) {
            q.fps = r.number(j["fps"], "/fps").value_or(q.fps);
            if (!(q.fps > 0 && q.fps <= 240)) r.check("", "fps", "must be in (0, 240]");
        }
        if (j.contains("start")) q.start = boundedNumber(r, j["start"], "/start", -1e9, 1e9, 0);
        if (j.contains("end")) q.end = boundedNumber(r, j["end"], "/end", -1e9, 1e9, 0);
        if (j.contains("video")) q.video = r.boolean(j["video"], "/video").value_or(false);
        readFrameOptions(r, j, q.output, q.settings, q.exposure);
    }
    r.throwIfErrors();
    return q;
}

}  // namespace volstyle::protocol
