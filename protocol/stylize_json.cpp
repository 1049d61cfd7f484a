#include "protocol/stylize_json.h"

#include "protocol/render_json.h"

namespace volstyle::protocol {
namespace {

void notYet(JsonReader& r, const nlohmann::json& j, const std::string& path, const char* field, const char* what) {
    if (j.contains(field)) r.fail(path + "/" + field, std::string(what) + " is not rendered yet (issue #11); remove it");
}

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
            auto v = r.number(j[size_t(4 * c + row)], path + "/" + std::to_string(4 * c + row));
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

/// {"closing": {"radius_px": 4, "shape": "disc"|"box"}}; dilation and holes are not rendered yet.
core::Manipulation manipulationFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path) {
    core::Manipulation m;
    if (!r.object(j, path, {"closing", "dilation", "holes"})) return m;
    notYet(r, j, path, "dilation", "epipolar dilation");
    notYet(r, j, path, "holes", "hole creation");
    if (j.contains("closing") && r.object(j["closing"], path + "/closing", {"radius_px", "shape"})) {
        const auto& c = j["closing"];
        if (!c.contains("radius_px")) r.fail(path + "/closing/radius_px", "is required");
        else m.closingRadius = r.integer(c["radius_px"], path + "/closing/radius_px").value_or(0);
        if (m.closingRadius < 0 || m.closingRadius > 64) r.check(path + "/closing", "radius_px", "must be in [0, 64]");
        const std::string shape = c.contains("shape") ? r.string(c["shape"], path + "/closing/shape").value_or("disc") : "disc";
        if (shape == "box") m.closingShape = core::MorphShape::Box;
        else if (shape != "disc") r.fail(path + "/closing/shape", "must be 'disc' or 'box', got '" + shape + "'");
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

StylizerSceneRequest stylizerSceneFromJson(const nlohmann::json& j, const std::string& path) {
    JsonReader r;
    StylizerSceneRequest out;
    core::StylizerScene& s = out.scene;
    if (r.object(j, path, {"occluders", "light", "medium", "camera", "background", "time", "transfer_function", "volume"})) {
        if (j.contains("transfer_function")) {
            const auto& t = j["transfer_function"];
            const std::string tp = path + "/transfer_function";
            if (r.object(t, tp, {"image", "mode", "depth_range"})) {
                core::TransferFunction tf;
                if (!t.contains("image")) r.fail(tp + "/image", "is required");
                else out.transferImageRef = r.string(t["image"], tp + "/image");
                const std::string mode = t.contains("mode") ? r.string(t["mode"], tp + "/mode").value_or("") : "multiply";
                if (mode == "replace") tf.mode = core::TransferFunction::Mode::Replace;
                else if (mode != "multiply" && !mode.empty()) r.fail(tp + "/mode", "must be 'multiply' or 'replace', got '" + mode + "'");
                if (t.contains("depth_range")) {
                    const auto& d = t["depth_range"];
                    if (!d.is_array() || d.size() != 2) {
                        r.fail(tp + "/depth_range", "must be [near, far]");
                    } else {
                        auto a = r.number(d[0], tp + "/depth_range/0"), b = r.number(d[1], tp + "/depth_range/1");
                        if (a && b && !(*b > *a)) r.fail(tp + "/depth_range", "far must be larger than near");
                        if (a && b) tf.depthNear = *a, tf.depthFar = *b;
                    }
                }
                s.transferFunction = tf;
            }
        }
        notYet(r, j, path, "volume", "a heterogeneous medium");
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
                if (type == "spot") r.fail(lp + "/type", "spot lights are not rendered yet (issue #11); use 'directional'");
                else if (type != "directional" && !type.empty()) r.fail(lp + "/type", "must be 'directional' or 'spot', got '" + type + "'");
                if (l.contains("direction")) s.light.direction = r.vec3(l["direction"], lp + "/direction").value_or(s.light.direction);
                // Spot lights' fields: spot lights are not rendered yet, and a directional light has no use for them.
                notYet(r, l, lp, "position", "a light's position (spot lights)");
                notYet(r, l, lp, "cone_deg", "a light's cone (spot lights)");
                if (l.contains("irradiance")) s.light.irradiance = r.vec3(l["irradiance"], lp + "/irradiance").value_or(s.light.irradiance);
                if (l.contains("shadow_map_size"))
                    s.light.shadowMapSize = r.integer(l["shadow_map_size"], lp + "/shadow_map_size").value_or(s.light.shadowMapSize);
                if (!(length(s.light.direction) > 0)) r.check(lp, "direction", "must not be zero");
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
        if (j.contains("time")) s.time = r.number(j["time"], path + "/time").value_or(0);
    }
    r.throwIfErrors();
    return out;
}

}  // namespace volstyle::protocol
