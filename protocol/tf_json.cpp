#include "protocol/tf_json.h"

#include <cmath>
#include <map>

namespace volstyle::protocol {
namespace {

nlohmann::json vec3Json(const Vec3d& v) { return {v.x, v.y, v.z}; }

/// A number in [0, 1] at `path`, or `fallback` when absent (a failure is recorded).
double unitNumber(JsonReader& r, const nlohmann::json& j, const char* field, const std::string& path, double fallback) {
    if (!j.contains(field)) return fallback;
    const auto v = r.number(j[field], path + "/" + field);
    if (!v) return fallback;
    if (!(*v >= 0 && *v <= 1)) {
        r.fail(path + "/" + field, "must be in [0, 1]");
        return fallback;
    }
    return *v;
}

Vec3d unitColour(JsonReader& r, const nlohmann::json& j, const std::string& path, Vec3d fallback) {
    if (!j.contains("colour")) return fallback;
    const auto v = r.vec3(j["colour"], path + "/colour");
    if (!v) return fallback;
    for (int k = 0; k < 3; ++k)
        if (!((*v)[k] >= 0 && (*v)[k] <= 1)) {
            r.fail(path + "/colour", "each component must be in [0, 1] (linear)");
            return fallback;
        }
    return *v;
}

core::TfConstraint constraintFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, bool positioned) {
    core::TfConstraint c;
    // A solid layer's colour and alpha are fields of the layer (checked there).
    if (positioned && !r.object(j, path, {"v_bar", "depth", "colour", "alpha", "anchor"})) return c;
    if (positioned) {
        for (const char* field : {"v_bar", "depth"})
            if (!j.contains(field) && !j.contains("anchor")) r.fail(path + "/" + field, "is required (or an anchor)");
        c.vBar = unitNumber(r, j, "v_bar", path, 0.5);
        c.depth = unitNumber(r, j, "depth", path, 0.5);
    }
    c.colour = unitColour(r, j, path, c.colour);
    c.alpha = unitNumber(r, j, "alpha", path, 1);
    if (positioned && j.contains("anchor")) {
        const auto& a = j["anchor"];
        const std::string ap = path + "/anchor";
        if (r.object(a, ap, {"position", "follow"})) {
            core::TfAnchor anchor;
            if (!a.contains("position")) r.fail(ap + "/position", "is required");
            else if (auto p = r.vec3(a["position"], ap + "/position")) {
                if (std::abs(p->x) <= 1e9 && std::abs(p->y) <= 1e9 && std::abs(p->z) <= 1e9) anchor.position = *p;
                else r.fail(ap + "/position", "must be finite (|x| <= 1e9)");
            }
            if (a.contains("follow")) anchor.follow = r.string(a["follow"], ap + "/follow").value_or("");
            c.anchor = anchor;
        }
    }
    return c;
}

const char* blendName(core::TfBlend b) { return b == core::TfBlend::Multiply ? "multiply" : b == core::TfBlend::Add ? "add" : "normal"; }
const char* kindName(core::TfLayerKind k) {
    switch (k) {
        case core::TfLayerKind::Gradient: return "gradient";
        case core::TfLayerKind::Image: return "image";
        case core::TfLayerKind::Diffusion: return "diffusion";
        case core::TfLayerKind::Solid: break;
    }
    return "solid";
}

/// At most this many layers and constraints a layer: a stack an artist builds by hand, and a
/// bound on what one request makes the server solve.
constexpr size_t kMaxLayers = 32, kMaxConstraints = 256;

core::TfLayer layerFromJson(JsonReader& r, const nlohmann::json& j, const std::string& path, SceneSource source, std::string& imageRef) {
    core::TfLayer l;
    if (!r.object(j, path, {"type", "blend", "opacity", "colour", "alpha", "from", "to", "image", "constraints"})) return l;
    const std::string type = j.contains("type") ? r.string(j["type"], path + "/type").value_or("") : "";
    const std::map<std::string, core::TfLayerKind> kinds = {{"solid", core::TfLayerKind::Solid},
                                                            {"gradient", core::TfLayerKind::Gradient},
                                                            {"image", core::TfLayerKind::Image},
                                                            {"diffusion", core::TfLayerKind::Diffusion}};
    if (auto it = kinds.find(type); it != kinds.end()) l.kind = it->second;
    else r.fail(path + "/type", "must be 'solid', 'gradient', 'image' or 'diffusion'" + (type.empty() ? std::string() : ", got '" + type + "'"));
    const std::string blend = j.contains("blend") ? r.string(j["blend"], path + "/blend").value_or("normal") : "normal";
    if (blend == "multiply") l.blend = core::TfBlend::Multiply;
    else if (blend == "add") l.blend = core::TfBlend::Add;
    else if (blend != "normal") r.fail(path + "/blend", "must be 'normal', 'multiply' or 'add', got '" + blend + "'");
    l.opacity = unitNumber(r, j, "opacity", path, 1);
    // Fields of the other kinds are mistakes, not ignored.
    auto only = [&](std::initializer_list<const char*> fields, core::TfLayerKind kind) {
        for (const char* f : fields)
            if (j.contains(f) && l.kind != kind) r.fail(path + "/" + f, std::string("belongs to a ") + kindName(kind) + " layer");
    };
    only({"colour", "alpha"}, core::TfLayerKind::Solid);
    only({"from", "to"}, core::TfLayerKind::Gradient);
    only({"constraints"}, core::TfLayerKind::Diffusion);
    if (j.contains("image") && l.kind != core::TfLayerKind::Image) r.fail(path + "/image", "belongs to an image layer");
    switch (l.kind) {
        case core::TfLayerKind::Solid: l.solid = constraintFromJson(r, j, path, false); break;
        case core::TfLayerKind::Gradient:
            for (auto [field, into] : {std::pair{"from", &l.from}, std::pair{"to", &l.to}}) {
                if (!j.contains(field)) r.fail(path + "/" + field, "is required");
                else *into = constraintFromJson(r, j[field], path + "/" + field, true);
            }
            break;
        case core::TfLayerKind::Image:
            if (source == SceneSource::Api) {
                if (j.contains("image")) r.fail(path + "/image", "the API takes no file paths: the layer shows the image PUT to …/stylizer/tf");
            } else if (!j.contains("image")) {
                r.fail(path + "/image", "is required (the image file)");
            } else {
                imageRef = r.string(j["image"], path + "/image").value_or("");
            }
            break;
        case core::TfLayerKind::Diffusion: {
            if (!j.contains("constraints")) break;  // none yet: a transparent layer
            const auto& list = j["constraints"];
            if (!list.is_array()) r.fail(path + "/constraints", "must be an array of constraints");
            else if (list.size() > kMaxConstraints) r.fail(path + "/constraints", "at most " + std::to_string(kMaxConstraints) + " constraints a layer");
            else
                for (size_t i = 0; i < list.size(); ++i)
                    l.constraints.push_back(constraintFromJson(r, list[i], path + "/constraints/" + std::to_string(i), true));
            break;
        }
    }
    return l;
}

}  // namespace

core::TransferFunction transferFunctionFromJson(JsonReader& r, const nlohmann::json& t, const std::string& tp, SceneSource source,
                                                std::vector<TfImageRef>& refs) {
    core::TransferFunction tf;
    if (!r.object(t, tp, {"image", "mode", "depth_range", "size", "layers"})) return tf;
    const bool layered = t.contains("layers");
    if (layered) {
        if (t.contains("image")) r.fail(tp + "/image", "a TF is an image or layers, not both (an image layer holds an image)");
        const auto& list = t["layers"];
        if (!list.is_array()) r.fail(tp + "/layers", "must be an array of layers");
        else if (list.size() > kMaxLayers) r.fail(tp + "/layers", "at most " + std::to_string(kMaxLayers) + " layers");
        else
            for (size_t i = 0; i < list.size(); ++i) {
                std::string ref;
                tf.layers.push_back(layerFromJson(r, list[i], tp + "/layers/" + std::to_string(i), source, ref));
                if (tf.layers.back().kind == core::TfLayerKind::Image) refs.push_back({int(i), ref});
            }
        if (list.is_array() && list.empty()) r.fail(tp + "/layers", "needs at least one layer (leave transfer_function out for none)");
    } else if (source == SceneSource::Api) {
        if (t.contains("image")) r.fail(tp + "/image", "the API takes no file paths: upload the image with PUT …/stylizer/tf and leave this out");
        refs.push_back({-1, ""});
    } else if (!t.contains("image")) {
        r.fail(tp + "/image", "is required (or layers)");
    } else {
        refs.push_back({-1, r.string(t["image"], tp + "/image").value_or("")});
    }
    if (t.contains("size")) {
        const auto& s = t["size"];
        if (!layered) r.fail(tp + "/size", "sizes a TF of layers (an image TF has the image's size)");
        else if (!s.is_array() || s.size() != 2) r.fail(tp + "/size", "must be [width, height]");
        else {
            auto w = r.integer(s[0], tp + "/size/0"), h = r.integer(s[1], tp + "/size/1");
            if (w && h && !(*w >= 1 && *w <= 1024 && *h >= 1 && *h <= 1024)) r.fail(tp + "/size", "must be 1–1024 texels a side");
            else if (w && h) tf.width = *w, tf.height = *h;
        }
    }
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
    return tf;
}

nlohmann::json tfConstraintToJson(const core::TfConstraint& c) {
    nlohmann::json j = {{"v_bar", c.vBar}, {"depth", c.depth}, {"colour", vec3Json(c.colour)}, {"alpha", c.alpha}};
    if (c.anchor) {
        j["anchor"] = {{"position", vec3Json(c.anchor->position)}};
        if (!c.anchor->follow.empty()) j["anchor"]["follow"] = c.anchor->follow;
    }
    return j;
}

nlohmann::json tfLayerToJson(const core::TfLayer& l) {
    nlohmann::json j = {{"type", kindName(l.kind)}, {"blend", blendName(l.blend)}, {"opacity", l.opacity}};
    switch (l.kind) {
        case core::TfLayerKind::Solid: j["colour"] = vec3Json(l.solid.colour), j["alpha"] = l.solid.alpha; break;
        case core::TfLayerKind::Gradient: j["from"] = tfConstraintToJson(l.from), j["to"] = tfConstraintToJson(l.to); break;
        case core::TfLayerKind::Image: break;
        case core::TfLayerKind::Diffusion: {
            nlohmann::json list = nlohmann::json::array();
            for (const auto& c : l.constraints) list.push_back(tfConstraintToJson(c));
            j["constraints"] = list;
            break;
        }
    }
    return j;
}

nlohmann::json transferFunctionToJson(const core::TransferFunction& tf, const std::optional<std::string>& imageRef) {
    nlohmann::json j = {{"mode", tf.mode == core::TransferFunction::Mode::Replace ? "replace" : "multiply"},
                        {"depth_range", {tf.depthNear, tf.depthFar}}};
    if (!tf.layers.empty()) {
        nlohmann::json layers = nlohmann::json::array();
        for (const auto& l : tf.layers) layers.push_back(tfLayerToJson(l));
        j["layers"] = layers;
        j["size"] = {tf.width, tf.height};
    } else if (imageRef) {
        j["image"] = *imageRef;
    }
    return j;
}

}  // namespace volstyle::protocol
