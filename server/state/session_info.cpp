#include "server/state/session_info.h"

#include <tuple>

namespace volstyle::server {

protocol::ViewInfo viewInfo(const SessionView& v) {
    return {v.id, v.camera, v.target.has_value(), v.weights.has_value(), bool(v.background), v.frame, v.clippedPixels};
}

std::vector<protocol::ViewInfo> viewInfos(Session& s) {
    std::lock_guard lock(s.mutex);
    std::vector<protocol::ViewInfo> out;
    for (const auto& v : s.views.list) out.push_back(viewInfo(v));
    return out;
}

protocol::SessionInfo sessionInfo(Session& s) {
    std::lock_guard lock(s.mutex);
    return sessionInfoLocked(s);
}

protocol::SessionInfo sessionInfoLocked(const Session& s) {
    const core::Volume& v = s.volume.current;
    protocol::SessionInfo info;
    info.id = s.id, info.created = s.created, info.scene = s.scene;
    info.dims = v.dims();
    std::tie(info.lo, info.hi) = v.worldBounds();
    info.voxelSize = v.voxelSize();
    info.sparse = v.isSparse();
    info.activeVoxels = int64_t(v.activeVoxels());
    info.bytes = int64_t(v.memoryBytes());
    info.grids = {"extinction"};
    if (v.hasAlbedo()) info.grids.push_back("albedo");
    if (v.hasEmission()) info.grids.push_back("emission");
    if (v.refractiveIndex()) info.grids.push_back("refractive_index");
    info.version = s.volume.version;
    info.shows = s.volume.shows;
    info.undo = int(s.volume.undo.size());
    info.redo = int(s.volume.redo.size());
    info.lighting = s.light.lighting;
    info.environmentMap = s.light.environmentMap;
    for (const auto& view : s.views.list) info.views.push_back(viewInfo(view));
    info.jobs = s.jobs;
    const auto& numbers = s.volume.versions.numbers();
    info.versions.assign(numbers.begin(), numbers.end());
    for (const auto& d : s.damaged) info.damaged.emplace_back(d.file, d.reason);
    info.environmentMapInfo = environmentMapInfo(s);
    return info;
}

std::vector<protocol::FrameInfo> frameInfos(Session& s) {
    std::lock_guard lock(s.mutex);
    std::vector<protocol::FrameInfo> out;
    for (const auto& [n, f] : s.frames) {
        int views = 0;
        for (const auto& v : s.views.list) views += v.frame == n ? 1 : 0;
        out.push_back({n, f.volume.dims(), f.volume.isSparse(), f.volume.activeVoxels(), f.solved, views});
    }
    return out;
}

}  // namespace volstyle::server
