// What is in a VDB file (volstyle info) and what a round trip lost (volstyle convert, tests).
#include <openvdb/openvdb.h>

#include <limits>
#include <sstream>

#include "core/volume/vdb_file.h"
#include "core/volume/vdb_io.h"

namespace volstyle::core {

using namespace vdb_file;

std::vector<VdbGridInfo> inspectVdb(const std::string& path) {
    FileContents file = readVdbFile(path);
    std::vector<VdbGridInfo> out;
    for (const auto& g : file.grids) {
        VdbGridInfo info;
        info.name = g->getName();
        info.type = g->valueType();
        info.gridClass = openvdb::GridBase::gridClassToMenuName(g->getGridClass());
        info.activeVoxels = int64_t(g->activeVoxelCount());
        openvdb::CoordBBox box = g->evalActiveVoxelBoundingBox();
        info.activeMin = {box.min().x(), box.min().y(), box.min().z()};
        info.activeMax = {box.max().x(), box.max().y(), box.max().z()};
        openvdb::Vec3d vs = g->voxelSize();
        info.voxelSize = {vs.x(), vs.y(), vs.z()};
        info.isLinearTransform = g->transform().isLinear();
        if (info.isLinearTransform) info.worldFromIndex = fromVdb(g->transform().baseMap()->getAffineMap()->getMat4());
        Vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
        auto scan = [&](auto typed) {
            for (auto it = typed->cbeginValueOn(); it; ++it) {
                openvdb::Vec3s v(*it);
                for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], v[c]), hi[c] = std::max(hi[c], v[c]);
            }
        };
        if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(g)) scan(f);
        else if (auto v = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(g)) scan(v);
        if (info.activeVoxels == 0 || lo.x > hi.x) lo = hi = Vec3(0.0f);
        info.minValue = lo, info.maxValue = hi;
        for (auto it = g->beginMeta(); it != g->endMeta(); ++it)
            info.metadata.emplace_back(it->first, it->second->str());
        out.push_back(info);
    }
    return out;
}

std::vector<std::pair<std::string, std::string>> vdbFileMetadata(const std::string& path) {
    FileContents file = readVdbFile(path);
    std::vector<std::pair<std::string, std::string>> out;
    for (auto it = file.metadata.beginMeta(); it != file.metadata.endMeta(); ++it)
        out.emplace_back(it->first, it->second->str());
    return out;
}

namespace {

/// Metadata a round trip may change: OpenVDB's statistics (recomputed on every write) and the dense
/// box volstyle records.
bool isBookkeeping(const std::string& key) {
    return key.rfind("file_", 0) == 0 || key == kBoxMinKey || key == kBoxMaxKey || key == kMatrixKey;
}

void compareMetadata(const openvdb::MetaMap& a, const openvdb::MetaMap& b, const std::string& where,
                     std::vector<std::string>& out) {
    for (auto it = a.beginMeta(); it != a.endMeta(); ++it) {
        if (isBookkeeping(it->first)) continue;
        auto other = b[it->first];
        if (!other) out.push_back(where + ": metadata '" + it->first + "' is missing");
        else if (other->typeName() != it->second->typeName() || other->str() != it->second->str())
            out.push_back(where + ": metadata '" + it->first + "' was " + it->second->str() + ", is " + other->str());
    }
}

/// Active voxels and values: every active voxel of `a` active in `b` with the same value, and as
/// many active voxels (so none were added).
template <typename GridT>
void compareValues(const GridT& a, const GridT& b, const std::string& where, std::vector<std::string>& out) {
    if (a.activeVoxelCount() != b.activeVoxelCount()) {
        out.push_back(where + ": " + std::to_string(a.activeVoxelCount()) + " active voxels became " +
                      std::to_string(b.activeVoxelCount()));
        return;
    }
    auto acc = b.getConstAccessor();
    for (auto it = a.cbeginValueOn(); it; ++it) {
        openvdb::CoordBBox span;
        it.getBoundingBox(span);  // a tile spans many voxels
        for (auto ijk = span.begin(); ijk; ++ijk) {
            if (!acc.isValueOn(*ijk) || acc.getValue(*ijk) != *it) {
                std::ostringstream s;
                s << where << ": voxel " << *ijk << " was " << *it << (acc.isValueOn(*ijk) ? ", is " : ", is inactive ")
                  << acc.getValue(*ijk);
                out.push_back(s.str());
                return;
            }
        }
    }
    if (a.background() != b.background()) out.push_back(where + ": the background changed");
}

}  // namespace

std::vector<std::string> vdbDifferences(const std::string& before, const std::string& after, bool values) {
    const FileContents a = readVdbFile(before), b = readVdbFile(after);
    std::vector<std::string> out;
    compareMetadata(a.metadata, b.metadata, "file", out);
    for (const auto& ga : a.grids) {
        const std::string where = "grid '" + ga->getName() + "'";
        auto gb = findGrid(b.grids, ga->getName());
        if (!gb) {
            out.push_back(where + " is missing");
            continue;
        }
        if (ga->valueType() != gb->valueType())
            out.push_back(where + ": type " + ga->valueType() + " became " + gb->valueType());
        if (ga->getGridClass() != gb->getGridClass())
            out.push_back(where + ": class " + openvdb::GridBase::gridClassToString(ga->getGridClass()) + " became " +
                          openvdb::GridBase::gridClassToString(gb->getGridClass()));
        if (!(ga->transform() == gb->transform())) out.push_back(where + ": the transform changed");
        if (ga->voxelSize() != gb->voxelSize()) out.push_back(where + ": the voxel size changed");
        compareMetadata(*ga, *gb, where, out);
        if (ga->evalActiveVoxelBoundingBox() != gb->evalActiveVoxelBoundingBox()) {
            std::ostringstream s;
            s << where << ": the active index box " << ga->evalActiveVoxelBoundingBox() << " became "
              << gb->evalActiveVoxelBoundingBox();
            if (values) out.push_back(s.str());
        }
        if (!values || ga->valueType() != gb->valueType()) continue;
        if (auto fa = openvdb::gridConstPtrCast<openvdb::FloatGrid>(ga))
            compareValues(*fa, *openvdb::gridConstPtrCast<openvdb::FloatGrid>(gb), where, out);
        else if (auto va = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(ga))
            compareValues(*va, *openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(gb), where, out);
        else if (ga->activeVoxelCount() != gb->activeVoxelCount())
            out.push_back(where + ": the active voxel count changed");
    }
    return out;
}

}  // namespace volstyle::core
