// Writing OpenVDB files (with vdb_read.cpp and vdb_inspect.cpp the only translation units that
// include OpenVDB headers, through vdb_file.h).
//
// Lossless round trips (issue #10): a volume read from a file keeps the file's grids (VdbSource),
// and saveVdb writes a grid back untouched when the volume did not change it, patches only the
// changed voxels into a copy when it did, and writes every grid volstyle does not use as it was.
// Grids made from scratch (built-in scenes) are written so that reading them gives the same
// volume bit for bit: each grid's background is the value absent voxels have in the volume (albedo
// 1, everything else 0), and the box is recorded when the active voxels do not span it. A sparse
// volume writes only its active bricks' voxels: the file's topology, plus what a solve activated.

#include "core/volume/vdb_io.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>

#include <filesystem>
#include <limits>

#include "core/base/errors.h"
#include "core/volume/vdb_file.h"

namespace volstyle::core {

using namespace vdb_role;
using namespace vdb_file;
namespace fs = std::filesystem;

namespace {

/// Sets every voxel the volume holds (its box, or its active bricks) whose value in `grid` differs from the volume's: on an empty
/// grid, the voxels that differ from the background become active leaf voxels (never tiles, which
/// Blender's Cycles 3.4 renders as empty); on a copy of the file's grid, only changed voxels are
/// touched and its topology, tiles and values outside the box stay. Voxels where `activeIn` (an
/// RGB grid of the volume) is non-zero are made active even at the background value.
template <typename GridT>
void writeVoxels(GridT& grid, const openvdb::Coord& origin, const Volume& volume, const std::vector<float>& rgb,
                 const std::vector<float>* activeIn = nullptr) {
    using Value = typename GridT::ValueType;
    auto acc = grid.getAccessor();
    forEachActiveVoxel(volume, [&](Int3 p, size_t n) {
        Value v;
        if constexpr (std::is_same_v<Value, float>) v = rgb[3 * n];
        else v = Value(rgb[3 * n], rgb[3 * n + 1], rgb[3 * n + 2]);
        const openvdb::Coord ijk = origin + openvdb::Coord(p.x, p.y, p.z);
        const bool keep = activeIn && ((*activeIn)[3 * n] > 0 || (*activeIn)[3 * n + 1] > 0 || (*activeIn)[3 * n + 2] > 0);
        if (keep || acc.getValue(ijk) != v) acc.setValue(ijk, v);
    });
}

/// A grid of `float` (grey data) or Vec3f holding `rgb`. With `like`, the grid continues it: same
/// name, class and metadata, and (when `patch`) its tree, with only the changed voxels rewritten.
/// `activeIn`: see writeVoxels.
openvdb::GridBase::Ptr makeRoleGrid(Role role, const std::vector<float>& rgb, bool asFloat,
                                    const openvdb::GridBase::ConstPtr& like, bool patch, const openvdb::Coord& origin,
                                    const Volume& volume, const openvdb::math::Transform::Ptr& xf,
                                    const std::vector<float>* activeIn = nullptr) {
    auto build = [&](auto typed) -> openvdb::GridBase::Ptr {
        using GridT = typename decltype(typed)::element_type;
        typename GridT::Ptr grid;
        if (patch) {
            grid = openvdb::gridPtrCast<GridT>(like->deepCopyGrid());
            grid->setTransform(sharedTransform(*like));  // the deep copy's transform lost bits
        } else {
            const float b = absentValue(role);
            grid = GridT::create(typename GridT::ValueType(b));
            if (like) static_cast<openvdb::MetaMap&>(*grid) = static_cast<const openvdb::MetaMap&>(*like);
            grid->setTransform(xf);
        }
        writeVoxels(*grid, origin, volume, rgb, activeIn);
        if (!patch) openvdb::tools::pruneInactive(grid->tree());  // only inactive background goes
        return grid;
    };
    openvdb::GridBase::Ptr g = asFloat ? build(openvdb::FloatGrid::Ptr()) : build(openvdb::Vec3SGrid::Ptr());
    if (!like) {
        const bool colourExtinction = role == kExtinction && !asFloat;
        g->setName(colourExtinction ? "extinction" : roleNames(role).back());
        if (role == kExtinction) g->setGridClass(openvdb::GRID_FOG_VOLUME);
        g->insertMeta("creator", openvdb::StringMetadata("volstyle"));
    }
    return g;
}

/// The grid that stores one role of `volume` in the written file.
openvdb::GridBase::ConstPtr writeRole(Role role, const Volume& volume, const VdbSource* source, bool sameIndexSpace,
                                      const openvdb::Coord& origin, const openvdb::math::Transform::Ptr& xf) {
    const std::vector<float> rgb = denseOfVolume(volume, role);
    const openvdb::GridBase::ConstPtr like = source ? source->roles[role] : nullptr;
    if (rgb.empty()) return like;  // not in the volume (never happens for a grid it was read with)
    const bool grey = Volume::isGrey(rgb);
    if (like && sameIndexSpace) {
        const auto& reference = *source->roles[kExtinction];
        if (readRole(role, like, reference, origin, volume, "") == rgb) return like;  // unchanged: the file's own grid
        const bool wasFloat = like->isType<openvdb::FloatGrid>();
        const bool sameType = wasFloat ? grey : true;
        if (sameType && like->transform() == reference.transform())
            return makeRoleGrid(role, rgb, wasFloat, like, /*patch=*/true, origin, volume, xf);
    }
    // Made from scratch; a float grid of the file stays float while the data stays grey.
    const bool asFloat = like ? (like->isType<openvdb::FloatGrid>() && grey)
                              : (role == kRefractiveIndex || (role == kExtinction && grey));
    // Albedo's voxels inside the medium are active even where they are the background's 1:
    // Blender's Cycles reads an inactive voxel as 0 (a white cloud would render black there).
    return makeRoleGrid(role, rgb, asFloat, like, /*patch=*/false, origin, volume, xf, role == kAlbedo ? &volume.extinction() : nullptr);
}

}  // namespace

void saveVdb(const std::string& path, const Volume& volume) {
    initOpenVdb();
    VolumeLimits unlimited;
    unlimited.maxVoxels = unlimited.maxActiveVoxels = unlimited.maxSparseBytes = std::numeric_limits<int64_t>::max();
    unlimited.maxSide = unlimited.maxSparseSide = std::numeric_limits<int>::max();
    volume.validate(unlimited);
    const VdbSource* source = volume.vdbSource().get();
    // The file's index space and transform are reused while the volume still lives in them.
    const bool sameIndexSpace = source && source->dims == volume.dims() && source->worldFromIndex == volume.worldFromIndex();
    const openvdb::Coord origin = sameIndexSpace ? source->origin : openvdb::Coord(0, 0, 0);
    openvdb::math::Transform::Ptr xf =
        sameIndexSpace ? sharedTransform(*source->roles[kExtinction])
                       : openvdb::math::Transform::createLinearTransform(toVdb(volume.worldFromIndex()));

    std::array<openvdb::GridBase::ConstPtr, kRoleCount> written;
    for (int r = 0; r < kRoleCount; ++r) written[r] = writeRole(Role(r), volume, source, sameIndexSpace, origin, xf);

    // Record the dense box when the extinction's active voxels do not span it, and the exact matrix
    // of a transform made here (and drop records copied from the file that no longer hold).
    const Int3 d = volume.dims();
    const openvdb::CoordBBox box(origin, origin + openvdb::Coord(d.x - 1, d.y - 1, d.z - 1));
    openvdb::MetaMap meta = static_cast<const openvdb::MetaMap&>(*written[kExtinction]);
    meta.removeMeta(kBoxMinKey);
    meta.removeMeta(kBoxMaxKey);
    if (!sameIndexSpace) {  // in the file's index space its record (if any) still holds
        meta.removeMeta(kMatrixKey);
        meta.insertMeta(kMatrixKey, openvdb::Mat4DMetadata(toVdb(volume.worldFromIndex())));
    }
    if (written[kExtinction]->evalActiveVoxelBoundingBox() != box) {
        meta.insertMeta(kBoxMinKey, openvdb::Vec3IMetadata(box.min().asVec3i()));
        meta.insertMeta(kBoxMaxKey, openvdb::Vec3IMetadata(box.max().asVec3i()));
    }
    if (!(meta == static_cast<const openvdb::MetaMap&>(*written[kExtinction])))
        written[kExtinction] = written[kExtinction]->copyGridReplacingMetadata(meta);  // shares the tree

    // The file's grids in their order, each role replaced by what was written; then new roles.
    openvdb::GridCPtrVec grids;
    auto roleOf = [&](const openvdb::GridBase::ConstPtr& g) {
        for (int r = 0; r < kRoleCount; ++r)
            if (source && source->roles[r] == g) return r;
        return -1;
    };
    if (source) {
        for (const auto& g : source->grids) {
            const int r = roleOf(g);
            grids.push_back(r < 0 ? g : written[r]);
        }
    }
    for (int r = 0; r < kRoleCount; ++r)
        if (written[r] && (!source || !source->roles[r])) grids.push_back(written[r]);

    // Atomic replace: a crash mid-write never leaves a half-written file under `path`.
    const std::string tmp = path + ".tmp";
    try {
        openvdb::io::File file(tmp);
        file.write(grids, source ? source->fileMetadata : openvdb::MetaMap());
        file.close();
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError("cannot write " + quoted(path) + ": " + e.what());
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw IoError("cannot move " + quoted(tmp) + " to " + quoted(path) + ": " + ec.message());
}

}  // namespace volstyle::core
