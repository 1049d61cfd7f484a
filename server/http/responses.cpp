#include "server/http/responses.h"

#include "protocol/render_json.h"

namespace volstyle::server {
namespace {

nlohmann::json vec(const Vec3d& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace

nlohmann::json viewJson(const SessionView& v) {
    nlohmann::json j = {{"id", v.id}, {"camera", protocol::cameraToJson(v.camera)}, {"has_target", v.target.has_value()},
                        {"has_weights", v.weights.has_value()}, {"has_background", bool(v.background)}};
    if (v.frame) j["frame"] = *v.frame;
    return j;
}

nlohmann::json viewsJson(const Session& s) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& v : s.views.list) list.push_back(viewJson(v));
    return list;
}

nlohmann::json damagedJson(const std::vector<DamagedFile>& damaged) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& d : damaged) list.push_back({{"file", d.file}, {"reason", d.reason}});
    return list;
}

nlohmann::json sessionJson(Session& s) {
    std::lock_guard lock(s.mutex);
    const core::Volume& v = s.volume.current;
    auto [lo, hi] = v.worldBounds();
    nlohmann::json grids = nlohmann::json::array({"extinction"});
    if (v.hasAlbedo()) grids.push_back("albedo");
    if (v.hasEmission()) grids.push_back("emission");
    if (v.refractiveIndex()) grids.push_back("refractive_index");
    nlohmann::json j = {{"id", s.id},
            {"created", s.created},
            {"scene", s.scene},
            {"volume", {{"dims", {v.dims().x, v.dims().y, v.dims().z}}, {"bbox", {vec(lo), vec(hi)}},
                        {"voxel_size", vec(v.voxelSize())}, {"grids", grids}, {"version", s.volume.version}}},
            {"lighting", protocol::lightingToJson(s.light.lighting, s.light.environmentMap.get())},
            {"views", viewsJson(s)},
            {"jobs", s.jobs},
            {"versions", s.volume.versions.numbers()},
            {"damaged", damagedJson(s.damaged)}};
    if (auto map = environmentMapInfo(s))
        j["environment_map"] = nlohmann::json{{"width", map->width}, {"height", map->height}, {"used", map->used}};
    return j;
}

}  // namespace volstyle::server
