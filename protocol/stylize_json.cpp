// The stylizer's frame, pick and sequence requests (SPEC §7); the scene's JSON is in
// stylize_scene_json.cpp.
#include "protocol/stylize_json.h"

#include <algorithm>
#include <cmath>

#include "protocol/render_json.h"

namespace volstyle::protocol {

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
