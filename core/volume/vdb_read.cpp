// Reading OpenVDB files. With vdb_write.cpp and vdb_inspect.cpp the only translation units that
// include OpenVDB headers (through vdb_file.h).
//
// A file is read dense over its extinction grid's active box when that box fits the dense limits
// (as before issue #39), else sparse: as the 8³ bricks its leaf nodes and active tiles cover
// (brick_layout.h), counted and checked against the limits before anything is allocated, so a
// 2048³ box with a few percent active loads in proportion to what is active. The volume keeps the
// file's grids (VdbSource) so vdb_write.cpp can write it back without loss.

#include "core/volume/vdb_io.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Prune.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

#include "core/base/errors.h"
#include "core/volume/vdb_file.h"

// Reading whole files (vdb_file.h), shared with vdb_inspect.cpp.
namespace volstyle::core::vdb_file {
namespace {

namespace fs = std::filesystem;

/// OpenVDB's magic number, the first 4 bytes of every .vdb file (little-endian 0x56444220).
bool startsLikeVdb(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    return in.gcount() == 4 && std::memcmp(magic, "\x20\x42\x44\x56", 4) == 0;
}

}  // namespace

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::GridBase::ConstPtr findGrid(const openvdb::GridCPtrVec& grids, const std::string& name) {
    for (const auto& g : grids)
        if (g->getName() == name) return g;
    return nullptr;
}

FileContents readVdbFile(const std::string& path) {
    initOpenVdb();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw IoError("no such file " + quoted(path));
    if (fs::is_directory(path, ec)) throw IoError(quoted(path) + " is a folder, not a VDB file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot open " + quoted(path) + " (permission denied?)");
    if (!startsLikeVdb(path))
        throw IoError(quoted(path) + " is not an OpenVDB file (it does not start with the VDB magic number)");
    // OpenVDB keeps reading a truncated file with garbage sizes and may allocate gigabytes. A
    // stream that throws on any short read stops it at the first missing byte instead.
    in.exceptions(std::ios::failbit | std::ios::badbit);
    try {
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        FileContents out;
        for (const auto& g : *stream.getGrids()) out.grids.push_back(g);
        if (auto meta = stream.getMetadata()) out.metadata = *meta;
        return out;
    } catch (const std::ios_base::failure&) {
        throw IoError(quoted(path) + " is truncated (it ends before its grids do)");
    } catch (const openvdb::Exception& e) {
        throw IoError(quoted(path) + " is not a readable OpenVDB file (corrupt or truncated): " + e.what());
    } catch (const std::bad_alloc&) {
        // Damaged block sizes make OpenVDB ask for more memory than exists (found by fuzzing).
        throw IoError(quoted(path) + " is damaged: reading it asks for more memory than its grids can need");
    } catch (const std::exception& e) {
        throw IoError(quoted(path) + " could not be read: " + e.what());
    }
}

namespace {

/// Writes value v (a float or Vec3s) at stored voxel n of an RGB grid.
template <typename V>
void put(std::vector<float>& out, size_t n, const V& v) {
    if constexpr (std::is_same_v<V, float>) out[3 * n] = out[3 * n + 1] = out[3 * n + 2] = v;
    else out[3 * n] = v[0], out[3 * n + 1] = v[1], out[3 * n + 2] = v[2];
}

/// The bricks of a sparse shape read straight from the grid: brick b's first voxel is a leaf
/// origin (the layout's offset lines them up), so a brick is one leaf, or one tile value.
template <typename GridT>
void readBricks(const GridT& grid, const openvdb::Coord& origin, const Volume& shape, std::vector<float>& out) {
    const BrickLayout& bricks = *shape.bricks();
    auto acc = grid.getConstAccessor();
    const auto background = grid.background();
    for (size_t n = 0; n < size_t(kBrickVoxels); ++n) put(out, n, background);
    for (size_t slot = 1; slot < bricks.slots(); ++slot) {
        const Int3 f = bricks.firstVoxel(bricks.brickOfSlot(slot));
        const openvdb::Coord base = origin + openvdb::Coord(f.x, f.y, f.z);
        size_t n = slot * size_t(kBrickVoxels);
        if (const auto* leaf = acc.probeConstLeaf(base)) {
            for (int z = 0; z < kBrickSide; ++z)
                for (int y = 0; y < kBrickSide; ++y)
                    for (int x = 0; x < kBrickSide; ++x, ++n) put(out, n, leaf->getValue(base + openvdb::Coord(x, y, z)));
        } else {
            const auto v = acc.getValue(base);  // a tile or the background: one value for the brick
            for (int i = 0; i < kBrickVoxels; ++i, ++n) put(out, n, v);
        }
    }
}

/// Calls f(Int3 brick) for every brick of `layout` that box `bb` (file index space) overlaps.
template <typename F>
void forBricksIn(openvdb::CoordBBox bb, const openvdb::Coord& origin, const BrickLayout& layout, F&& f) {
    const Int3 d = layout.dims();
    bb.intersect(openvdb::CoordBBox(origin, origin + openvdb::Coord(d.x - 1, d.y - 1, d.z - 1)));
    if (bb.empty()) return;
    const Int3 lo = layout.brickOf({bb.min().x() - origin.x(), bb.min().y() - origin.y(), bb.min().z() - origin.z()});
    const Int3 hi = layout.brickOf({bb.max().x() - origin.x(), bb.max().y() - origin.y(), bb.max().z() - origin.z()});
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) f(Int3{x, y, z});
}

/// Gives the bricks of `layout` that hold a leaf of `grid` inside its box a slot of their own.
template <typename GridT>
void activateLeafBricks(const GridT& grid, const openvdb::Coord& origin, BrickLayout& layout) {
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf)
        if (!leaf->isEmpty()) forBricksIn(leaf->getNodeBoundingBox(), origin, layout, [&](Int3 b) { layout.activate(b); });
}

/// Calls f(Int3 brick) for the bricks inside an active tile of `grid` (tiles sit above the leaves,
/// 8³-aligned: a brick is inside one tile or none).
template <typename GridT, typename F>
void forTileBricks(const GridT& grid, const openvdb::Coord& origin, const BrickLayout& layout, F&& f) {
    auto tile = grid.tree().cbeginValueOn();
    tile.setMaxDepth(GridT::TreeType::ValueOnCIter::LEAF_DEPTH - 1);  // stops before the leaves' voxels
    for (; tile; ++tile) {
        openvdb::CoordBBox bb;
        tile.getBoundingBox(bb);
        forBricksIn(bb, origin, layout, f);
    }
}

/// Calls f with the grid as its type (FloatGrid or Vec3SGrid); throws for any other.
template <typename F>
void withTypedGrid(const openvdb::GridBase::ConstPtr& grid, const std::string& path, F&& f) {
    if (auto g = openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid)) return f(*g);
    if (auto g = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(grid)) return f(*g);
    throw InvalidArgument("grid " + quoted(grid->getName()) + " in " + quoted(path) + " has type '" + grid->valueType() +
                          "'; volstyle reads float or vec3s grids");
}

}  // namespace

std::vector<float> readGrid(const openvdb::GridBase::ConstPtr& grid, const openvdb::GridBase& reference,
                            const openvdb::Coord& origin, const Volume& shape, const std::string& path) {
    std::vector<float> out(shape.storedVoxels() * 3, 0.0f);
    const bool sameTransform = grid->transform() == reference.transform();
    withTypedGrid(grid, path, [&](const auto& typed) {
        using GridT = std::decay_t<decltype(typed)>;
        if (sameTransform && shape.isSparse()) return readBricks(typed, origin, shape, out);
        auto acc = typed.getConstAccessor();
        openvdb::tools::GridSampler<typename GridT::ConstAccessor, openvdb::tools::BoxSampler> sampler(acc, typed.transform());
        if (shape.isSparse()) put(out, 0, typed.background()), std::fill(out.begin() + 3, out.begin() + 3 * kBrickVoxels, out[0]);
        forEachActiveVoxel(shape, [&](Int3 v, size_t n) {
            const openvdb::Coord ijk = origin + openvdb::Coord(v.x, v.y, v.z);
            put(out, n, openvdb::Vec3s(sameTransform ? acc.getValue(ijk) : sampler.wsSample(reference.transform().indexToWorld(ijk))));
        });
    });
    return out;
}

std::vector<float> readRole(vdb_role::Role role, const openvdb::GridBase::ConstPtr& grid, const openvdb::GridBase& reference,
                            const openvdb::Coord& origin, const Volume& shape, const std::string& path) {
    std::vector<float> rgb = readGrid(grid, reference, origin, shape, path);
    if (role == vdb_role::kRefractiveIndex)
        for (float& n : rgb) n = n == 0.0f ? 1.0f : n;  // a background of 0 is vacuum
    return rgb;
}

}  // namespace volstyle::core::vdb_file

namespace volstyle::core {

using namespace vdb_role;  // Role and the grid conventions (vdb_grid_roles.h)

namespace {

using namespace vdb_file;
namespace fs = std::filesystem;

/// The file index-to-world matrix of `grid`, or the exact one volstyle recorded if it agrees.
Mat4 recordedOrFileMatrix(const openvdb::GridBase& grid, const Mat4& fromFile) {
    auto recorded = grid.getMetadata<openvdb::Mat4DMetadata>(kMatrixKey);
    if (!recorded) return fromFile;
    const Mat4 exact = fromVdb(recorded->value());
    double scale = 0;
    for (double x : fromFile.m) scale = std::max(scale, std::abs(x));
    for (size_t i = 0; i < 16; ++i)
        if (std::abs(exact.m[i] - fromFile.m[i]) > 1e-12 * std::max(scale, 1.0)) return fromFile;  // edited elsewhere
    return exact;
}


Mat4 worldFromIndexOf(const openvdb::GridBase& grid, const std::string& path) {
    const openvdb::math::Transform& xf = grid.transform();
    if (!xf.isLinear()) {
        throw InvalidArgument("grid " + quoted(grid.getName()) + " in " + quoted(path) +
                              " has a non-linear (frustum) transform; only linear transforms are supported "
                              "(resample it to a linear transform, e.g. with Houdini's VDB Resample)");
    }
    return fromVdb(xf.baseMap()->getAffineMap()->getMat4());
}

std::string gridNames(const openvdb::GridCPtrVec& grids) {
    std::string s;
    for (const auto& g : grids) s += (s.empty() ? "" : ", ") + g->getName();
    return s.empty() ? "(none)" : s;
}

/// The index box the dense volume covers: the extinction grid's active voxels, widened to the box
/// volstyle recorded when it wrote the file.
openvdb::CoordBBox denseBox(const openvdb::GridBase& extinction) {
    openvdb::CoordBBox box = extinction.evalActiveVoxelBoundingBox();
    auto lo = extinction.getMetadata<openvdb::Vec3IMetadata>(kBoxMinKey);
    auto hi = extinction.getMetadata<openvdb::Vec3IMetadata>(kBoxMaxKey);
    if (lo && hi) {
        const openvdb::Coord a(lo->value()), b(hi->value());
        if (a.x() <= b.x() && a.y() <= b.y() && a.z() <= b.z()) box.expand(openvdb::CoordBBox(a, b));
    }
    return box;
}

/// Refuses NaN, infinite and out-of-range values naming the file's grid and the file's voxel.
void checkValues(Role role, const std::vector<float>& rgb, const openvdb::GridBase& grid, const openvdb::Coord& origin,
                 const Volume& shape, const std::string& path) {
    const float inf = std::numeric_limits<float>::max();
    const float lo = role == kRefractiveIndex ? 1.0f : 0.0f, hi = role == kAlbedo ? 1.0f : inf;
    InvalidValues bad = findInvalidValues(rgb, 3, lo, hi);
    if (bad.count == 0) return;
    const Int3 v = shape.voxelOfStored(bad.firstVoxel);
    const openvdb::Coord at = origin + openvdb::Coord(v.x, v.y, v.z);
    std::ostringstream s;
    s << "grid " << quoted(grid.getName()) << " in " << quoted(path) << " has " << bad.count
      << " voxel(s) with values that are not finite or outside [" << lo << ", " << (hi == inf ? "inf)" : "1]") << "; the first is "
      << bad.firstValue;
    if (v.x < 0) s << " (its background value)";
    else s << " at voxel " << at.x() << "," << at.y() << "," << at.z();
    throw InvalidArgument(s.str());
}

}  // namespace

namespace {

/// An empty sparse volume over the source's box, with every brick active that a leaf or an active
/// tile of its role grids (those in the extinction's index space) touches; the limits are checked
/// on the count, before any grid is allocated.
Volume sparseShape(const VdbSource& source, const VolumeLimits& limits, const std::string& path) {
    const openvdb::Coord o = source.origin;
    auto mod8 = [](int v) { return ((v % kBrickSide) + kBrickSide) % kBrickSide; };
    BrickLayout layout(source.dims, {mod8(o.x()), mod8(o.y()), mod8(o.z())});
    const auto& reference = *source.roles[kExtinction];
    int rgbGrids = 0;
    std::vector<openvdb::GridBase::ConstPtr> grids;  // the role grids read brick by brick
    for (int r = 0; r < kRoleCount; ++r) {
        const auto& grid = source.roles[r];
        if (!grid) continue;
        rgbGrids += r != kRefractiveIndex;
        if (grid->transform() == reference.transform()) grids.push_back(grid);
    }
    // Leaves first, a slot each; then the bricks inside tiles (and no leaf of any grid), which
    // share one slot per combination of the grids' values there.
    for (const auto& grid : grids) withTypedGrid(grid, path, [&](const auto& typed) { activateLeafBricks(typed, o, layout); });
    std::map<std::string, uint32_t> sharedSlots;
    auto valuesAt = [&](Int3 b) {
        const Int3 f = layout.firstVoxel(b);
        const openvdb::Coord base = o + openvdb::Coord(f.x, f.y, f.z);
        std::string key;
        for (const auto& grid : grids)
            withTypedGrid(grid, path, [&](const auto& typed) {
                const auto v = typed.tree().getValue(base);
                key.append(reinterpret_cast<const char*>(&v), sizeof(v));
            });
        return key;
    };
    for (const auto& grid : grids)
        withTypedGrid(grid, path, [&](const auto& typed) {
            forTileBricks(typed, o, layout, [&](Int3 b) {
                if (layout.isActive(b)) return;
                const auto [it, added] = sharedSlots.try_emplace(valuesAt(b), 0u);
                if (added) it->second = layout.addSharedSlot(b);
                layout.share(b, it->second);
            });
        });
    try {
        checkSparseLimits(source.dims, layout.activeBricks(), layout.slots(), rgbGrids, limits);
    } catch (const LimitExceeded& e) {
        throw LimitExceeded(std::string(e.what()) + " (in " + quoted(path) + ")");
    }
    return Volume(std::move(layout), source.worldFromIndex);
}

/// A volume from a file's grids (loadVdb after reading; loadVdbFrames per frame).
Volume volumeFromGrids(FileContents file, const std::string& path, const VolumeLimits& limits) {
    auto source = std::make_shared<VdbSource>();
    source->grids = file.grids;
    source->fileMetadata = file.metadata;
    for (int r = 0; r < kRoleCount; ++r)
        for (const auto& name : roleNames(Role(r)))
            if (!source->roles[r]) source->roles[r] = findGrid(file.grids, name);
    const auto& extinction = source->roles[kExtinction];
    if (!extinction) {
        throw InvalidArgument("neither an 'extinction' nor a 'density' grid in " + quoted(path) +
                              "; grids present: " + gridNames(file.grids) +
                              " (rename the grid that holds the medium's density to 'density')");
    }
    const openvdb::CoordBBox box = denseBox(*extinction);
    if (box.empty())
        throw InvalidArgument("grid " + quoted(extinction->getName()) + " in " + quoted(path) + " has no active voxels");
    // The box's extent in 64 bits: voxels at ±2e9 overflow OpenVDB's 32-bit Coord::dim().
    int64_t extent[3];
    for (int a = 0; a < 3; ++a) extent[a] = int64_t(box.max()[a]) - int64_t(box.min()[a]) + 1;
    const int64_t side = std::max({extent[0], extent[1], extent[2]});
    const bool fitsDense = side <= limits.maxSide && extent[0] * extent[1] * extent[2] <= limits.maxVoxels;  // sides ≤ 2³², product fits
    const bool sparse = limits.storage == VolumeStorage::Sparse || (limits.storage == VolumeStorage::Automatic && !fitsDense);
    if (sparse ? side > limits.maxSparseSide : !fitsDense) {
        std::ostringstream s;
        s << "the active box of " << quoted(extinction->getName()) << " in " << quoted(path) << " is " << extent[0] << "x"
          << extent[1] << "x" << extent[2] << " voxels, over the limit of ";
        if (sparse) s << limits.maxSparseSide << " voxels on a side";
        else s << limits.maxVoxels << " voxels (at most " << limits.maxSide << " on a side) for dense storage";
        throw LimitExceeded(s.str());
    }
    source->dims = Int3{int(extent[0]), int(extent[1]), int(extent[2])};
    source->origin = box.min();

    // Voxel (0,0,0) is the box's minimum corner.
    const openvdb::Coord o = box.min();
    const Int3 dims = source->dims;
    source->worldFromIndex = recordedOrFileMatrix(*extinction, worldFromIndexOf(*extinction, path)) *
                             Mat4::translate({double(o.x()), double(o.y()), double(o.z())});
    Volume volume = sparse ? sparseShape(*source, limits, path) : Volume(dims, source->worldFromIndex);
    for (int r = 0; r < kRoleCount; ++r) {
        const auto& grid = source->roles[r];
        if (!grid) continue;
        worldFromIndexOf(*grid, path);  // rejects frustum transforms
        std::vector<float> rgb = readRole(Role(r), grid, *extinction, o, volume, path);
        checkValues(Role(r), rgb, *grid, o, volume, path);
        switch (Role(r)) {
            case kExtinction: volume.extinction() = std::move(rgb); break;
            case kAlbedo: volume.albedo() = std::move(rgb); break;
            case kEmission: volume.emission() = std::move(rgb); break;
            default: {
                std::vector<float> n(volume.storedVoxels());
                for (size_t i = 0; i < n.size(); ++i) n[i] = rgb[3 * i];
                volume.refractiveIndex() = std::move(n);
            }
        }
    }
    try {
        volume.validate(limits);
    } catch (const LimitExceeded& e) {
        throw LimitExceeded(std::string(e.what()) + " (in " + quoted(path) + ")");
    } catch (const InvalidArgument& e) {
        throw InvalidArgument(std::string(e.what()) + " (in " + quoted(path) + ")");
    }
    volume.setVdbSource(std::move(source));
    return volume;
}

/// The frame a grid belongs to in a file that holds a whole animation — an integer `frame`
/// metadata entry, or a name ending in `.N` or `_N` — and its name without the number.
std::optional<std::pair<int, std::string>> frameOfGrid(const openvdb::GridBase& grid) {
    // An integer out of range is refused by name: int64 4294967301 once wrapped to frame 5.
    const auto stamped = [&](int64_t n) {
        if (n < 0 || n > vdb_role::kMaxGridFrame)
            throw InvalidArgument("grid " + quoted(grid.getName()) + " has the frame metadata " + std::to_string(n) + ", outside 0.." +
                                  std::to_string(vdb_role::kMaxGridFrame));
        return std::make_pair(int(n), grid.getName());
    };
    if (auto m = grid.getMetadata<openvdb::Int32Metadata>("frame")) return stamped(m->value());
    if (auto m = grid.getMetadata<openvdb::Int64Metadata>("frame")) return stamped(m->value());
    return frameOfGridName(grid.getName());
}

}  // namespace

Volume loadVdb(const std::string& path, const VolumeLimits& limits) { return volumeFromGrids(readVdbFile(path), path, limits); }

std::map<int, Volume> loadVdbFrames(const std::string& path, const VolumeLimits& limits) {
    const FileContents file = readVdbFile(path);
    std::map<int, FileContents> frames;
    for (const auto& g : file.grids) {
        const auto frame = frameOfGrid(*g);
        if (!frame) continue;
        openvdb::GridBase::Ptr copy = openvdb::ConstPtrCast<openvdb::GridBase>(g)->copyGrid();  // shares the tree; only the name changes
        copy->setName(frame->second);
        frames[frame->first].grids.push_back(copy);
        frames[frame->first].metadata = file.metadata;
    }
    std::map<int, Volume> out;
    for (auto& [n, contents] : frames) {
        try {
            out[n] = volumeFromGrids(std::move(contents), path, limits);
        } catch (const InvalidArgument& e) {
            throw InvalidArgument("frame " + std::to_string(n) + ": " + e.what());
        }
    }
    return out;
}

std::vector<float> velocityOf(const Volume& volume) {
    const auto& source = volume.vdbSource();
    if (!source) return {};
    openvdb::GridBase::ConstPtr grid;
    for (const char* name : {"vel", "v", "velocity"})
        if (!grid) grid = findGrid(source->grids, name);
    if (!grid) return {};
    if (!openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(grid))
        throw InvalidArgument("the velocity grid " + quoted(grid->getName()) + " is " + grid->valueType() + "; volstyle reads a vec3s velocity");
    std::vector<float> v = readGrid(grid, *source->roles[kExtinction], source->origin, volume, grid->getName());
    for (float x : v)
        if (!std::isfinite(x)) throw InvalidArgument("the velocity grid " + quoted(grid->getName()) + " has non-finite values");
    return v;
}


}  // namespace volstyle::core
