#include "protocol/response_json.h"

#include "protocol/render_json.h"
#include "protocol/tf_json.h"

namespace volstyle::protocol {
namespace {

nlohmann::json vec(const Vec3d& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace

nlohmann::json viewToJson(const ViewInfo& v) {
    nlohmann::json j = {{"id", v.id}, {"camera", cameraToJson(v.camera)}, {"has_target", v.hasTarget},
                        {"has_weights", v.hasWeights}, {"has_background", v.hasBackground}, {"clipped_pixels", v.clippedPixels}};
    if (v.frame) j["frame"] = *v.frame;
    return j;
}

nlohmann::json viewsToJson(const std::vector<ViewInfo>& views) {
    nlohmann::json list = nlohmann::json::array();
    for (const ViewInfo& v : views) list.push_back(viewToJson(v));
    return list;
}

nlohmann::json sessionToJson(const SessionInfo& s) {
    nlohmann::json damaged = nlohmann::json::array();
    for (const auto& [file, reason] : s.damaged) damaged.push_back({{"file", file}, {"reason", reason}});
    nlohmann::json j = {{"id", s.id},
                        {"created", s.created},
                        {"scene", s.scene},
                        {"volume", {{"dims", {s.dims.x, s.dims.y, s.dims.z}}, {"bbox", {vec(s.lo), vec(s.hi)}},
                                    {"voxel_size", vec(s.voxelSize)}, {"grids", s.grids},
                                    {"storage", s.sparse ? "sparse" : "dense"}, {"active_voxels", s.activeVoxels}, {"bytes", s.bytes},
                                    {"version", s.version},
                                    {"shows", s.shows}, {"undo", s.undo}, {"redo", s.redo}}},
                        {"lighting", lightingToJson(s.lighting, s.environmentMap.get())},
                        {"views", viewsToJson(s.views)},
                        {"jobs", s.jobs},
                        {"versions", s.versions},
                        {"damaged", damaged}};
    if (s.environmentMapInfo) j["environment_map"] = environmentMapToJson(*s.environmentMapInfo);
    return j;
}

nlohmann::json framesToJson(const std::vector<FrameInfo>& frames) {
    nlohmann::json list = nlohmann::json::array();
    for (const FrameInfo& f : frames) list.push_back({{"frame", f.frame},
                        {"dims", {f.dims.x, f.dims.y, f.dims.z}},
                        {"storage", f.sparse ? "sparse" : "dense"},
                        {"active_voxels", f.activeVoxels},
                        {"solved", f.solved},
                        {"views", f.views}});
    return list;
}

nlohmann::json environmentMapToJson(const EnvironmentMapInfo& m) { return {{"width", m.width}, {"height", m.height}, {"used", m.used}}; }

nlohmann::json occluderMeshToJson(const OccluderMeshInfo& m) {
    return {{"name", m.name},
            {"format", m.format},
            {"vertices", m.vertices},
            {"triangles", m.triangles},
            {"file_bytes", m.fileBytes},
            {"bounds", {{m.boundsLo.x, m.boundsLo.y, m.boundsLo.z}, {m.boundsHi.x, m.boundsHi.y, m.boundsHi.z}}},
            {"used", m.used}};
}

nlohmann::json transferImageToJson(const TransferImageInfo& t) {
    return {{"width", t.width}, {"height", t.height}, {"channels", t.channels}, {"used", t.used}};
}

nlohmann::json stylizerPickToJson(const StylizerPick& p) {
    return {{"x", p.x}, {"y", p.y}, {"v_bar", p.vBar}, {"depth", p.depth}, {"distance", p.distance},
            {"occluder", p.occluderName.empty() ? nlohmann::json() : nlohmann::json(p.occluderName)},
            {"position", {p.position.x, p.position.y, p.position.z}}};
}

nlohmann::json addedTfConstraintToJson(const AddedTfConstraint& a) {
    nlohmann::json body = {{"revision", a.revision}, {"layer", a.layer}, {"index", a.index},
                           {"constraint", tfConstraintToJson(a.constraint)}, {"pick", stylizerPickToJson(a.pick)}};
    if (a.key >= 0) body["key"] = a.key;
    return body;
}

}  // namespace volstyle::protocol
