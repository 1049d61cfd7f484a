// OpenVDB read/write. With vdb_inspect.cpp (info, convert's checks) the only translation units
// that include OpenVDB headers (through vdb_file.h).
//
// Lossless round trips (issue #10): a volume read from a file keeps the file's grids (VdbSource),
// and saveVdb writes a grid back untouched when the volume did not change it, patches only the
// changed voxels into a copy when it did, and writes every grid volstyle does not use as it was.
// Grids made from scratch (built-in scenes) are written so that reading them gives the same dense
// volume bit for bit: each grid's background is the value absent voxels have in the volume (albedo
// 1, everything else 0), and the dense box is recorded when the active voxels do not span it.

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
#include <mutex>
#include <sstream>

#include "core/base/errors.h"
#include "core/volume/vdb_file.h"
#include "core/volume/vdb_grid_roles.h"

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

}  // namespace volstyle::core::vdb_file

namespace volstyle::core {

using namespace vdb_role;  // Role and the grid conventions (vdb_grid_roles.h)

struct VdbSource {
    openvdb::GridCPtrVec grids;  ///< every grid of the file in its order, as read (never modified)
    openvdb::MetaMap fileMetadata;
    std::array<openvdb::GridBase::ConstPtr, kRoleCount> roles;  ///< the grids read as each role
    openvdb::Coord origin;  ///< file index of dense voxel (0,0,0)
    Int3 dims;
    Mat4 worldFromIndex;  ///< the volume's transform as read
};

namespace {

using namespace vdb_file;
namespace fs = std::filesystem;



openvdb::math::Mat4d toVdb(const Mat4& m) {
    openvdb::math::Mat4d r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(j, i) = m(i, j);
    return r;
}

/// The shared transform of a grid (OpenVDB's Transform::copy() re-simplifies the map: lossy).
openvdb::math::Transform::Ptr sharedTransform(const openvdb::GridBase& grid) {
    return openvdb::ConstPtrCast<openvdb::math::Transform>(grid.constTransformPtr());
}

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

/// Fills a dense RGB grid from a float or Vec3f VDB grid, voxel (i,j,k) of the dense grid being
/// index `origin + (i,j,k)` of `reference`. Direct lookups when the transforms agree, trilinear
/// world-space resampling otherwise.
std::vector<float> densify(const openvdb::GridBase::ConstPtr& grid, const openvdb::GridBase& reference,
                           const openvdb::Coord& origin, Int3 dims, const std::string& path) {
    std::vector<float> out(size_t(dims.volume()) * 3, 0.0f);
    const bool sameTransform = grid->transform() == reference.transform();
    auto fill = [&](auto typedGrid) {
        using GridT = typename decltype(typedGrid)::element_type;
        auto acc = typedGrid->getConstAccessor();
        openvdb::tools::GridSampler<typename GridT::ConstAccessor, openvdb::tools::BoxSampler> sampler(
            acc, typedGrid->transform());
        size_t n = 0;
        for (int k = 0; k < dims.z; ++k)
            for (int j = 0; j < dims.y; ++j)
                for (int i = 0; i < dims.x; ++i, ++n) {
                    const openvdb::Coord ijk = origin + openvdb::Coord(i, j, k);
                    openvdb::Vec3s v(sameTransform ? acc.getValue(ijk)
                                                   : sampler.wsSample(reference.transform().indexToWorld(ijk)));
                    out[3 * n] = v[0], out[3 * n + 1] = v[1], out[3 * n + 2] = v[2];
                }
    };
    if (auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid)) {
        fill(f);
    } else if (auto v = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(grid)) {
        fill(v);
    } else {
        throw InvalidArgument("grid " + quoted(grid->getName()) + " in " + quoted(path) + " has type '" +
                              grid->valueType() + "'; volstyle reads float or vec3s grids");
    }
    return out;
}

/// The dense grid of a role as read from its file grid (absent refractive index: vacuum).
std::vector<float> densifyRole(Role role, const openvdb::GridBase::ConstPtr& grid, const openvdb::GridBase& reference,
                               const openvdb::Coord& origin, Int3 dims, const std::string& path) {
    std::vector<float> rgb = densify(grid, reference, origin, dims, path);
    if (role == kRefractiveIndex)
        for (float& n : rgb) n = n == 0.0f ? 1.0f : n;  // a background of 0 is vacuum
    return rgb;
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
                 Int3 dims, const std::string& path) {
    const float inf = std::numeric_limits<float>::max();
    const float lo = role == kRefractiveIndex ? 1.0f : 0.0f, hi = role == kAlbedo ? 1.0f : inf;
    InvalidValues bad = findInvalidValues(rgb, 3, lo, hi);
    if (bad.count == 0) return;
    const size_t n = bad.firstVoxel;
    const openvdb::Coord at = origin + openvdb::Coord(int(n % size_t(dims.x)), int((n / size_t(dims.x)) % size_t(dims.y)),
                                                      int(n / (size_t(dims.x) * size_t(dims.y))));
    std::ostringstream s;
    s << "grid " << quoted(grid.getName()) << " in " << quoted(path) << " has " << bad.count
      << " voxel(s) with values that are not finite or outside [" << lo << ", " << (hi == inf ? "inf)" : "1]")
      << "; the first is " << bad.firstValue << " at voxel " << at.x() << "," << at.y() << "," << at.z();
    throw InvalidArgument(s.str());
}

}  // namespace

namespace {

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
    const bool sideOver = extent[0] > limits.maxSide || extent[1] > limits.maxSide || extent[2] > limits.maxSide;
    if (sideOver || extent[0] * extent[1] * extent[2] > limits.maxVoxels) {  // sides ≤ 2³², product fits
        std::ostringstream s;
        s << "the active box of " << quoted(extinction->getName()) << " in " << quoted(path) << " is " << extent[0]
          << "x" << extent[1] << "x" << extent[2] << " voxels, over the limit of " << limits.maxVoxels
          << " voxels (at most " << limits.maxSide << " on a side)";
        throw LimitExceeded(s.str());
    }
    source->dims = Int3{int(extent[0]), int(extent[1]), int(extent[2])};
    source->origin = box.min();

    // Dense voxel (0,0,0) is the box's minimum corner.
    const openvdb::Coord o = box.min();
    const Int3 dims = source->dims;
    source->worldFromIndex = recordedOrFileMatrix(*extinction, worldFromIndexOf(*extinction, path)) *
                             Mat4::translate({double(o.x()), double(o.y()), double(o.z())});
    Volume volume(dims, source->worldFromIndex);
    for (int r = 0; r < kRoleCount; ++r) {
        const auto& grid = source->roles[r];
        if (!grid) continue;
        worldFromIndexOf(*grid, path);  // rejects frustum transforms
        std::vector<float> rgb = densifyRole(Role(r), grid, *extinction, o, dims, path);
        checkValues(Role(r), rgb, *grid, o, dims, path);
        switch (Role(r)) {
            case kExtinction: volume.extinction() = std::move(rgb); break;
            case kAlbedo: volume.albedo() = std::move(rgb); break;
            case kEmission: volume.emission() = std::move(rgb); break;
            default: {
                std::vector<float> n(volume.voxelCount());
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
    std::vector<float> v = densify(grid, *source->roles[kExtinction], source->origin, source->dims, grid->getName());
    for (float x : v)
        if (!std::isfinite(x)) throw InvalidArgument("the velocity grid " + quoted(grid->getName()) + " has non-finite values");
    return v;
}

namespace {

/// Sets every voxel of the dense box whose value in `grid` differs from the volume's: on an empty
/// grid, the voxels that differ from the background become active leaf voxels (never tiles, which
/// Blender's Cycles 3.4 renders as empty); on a copy of the file's grid, only changed voxels are
/// touched and its topology, tiles and values outside the box stay. Voxels where `activeIn` (a
/// dense RGB grid) is non-zero are made active even at the background value.
template <typename GridT>
void writeDense(GridT& grid, const openvdb::Coord& origin, Int3 dims, const std::vector<float>& rgb,
                const std::vector<float>* activeIn = nullptr) {
    using Value = typename GridT::ValueType;
    auto acc = grid.getAccessor();
    size_t n = 0;
    for (int k = 0; k < dims.z; ++k)
        for (int j = 0; j < dims.y; ++j)
            for (int i = 0; i < dims.x; ++i, ++n) {
                Value v;
                if constexpr (std::is_same_v<Value, float>) v = rgb[3 * n];
                else v = Value(rgb[3 * n], rgb[3 * n + 1], rgb[3 * n + 2]);
                const openvdb::Coord ijk = origin + openvdb::Coord(i, j, k);
                const bool keep = activeIn && ((*activeIn)[3 * n] > 0 || (*activeIn)[3 * n + 1] > 0 || (*activeIn)[3 * n + 2] > 0);
                if (keep || acc.getValue(ijk) != v) acc.setValue(ijk, v);
            }
}

/// A grid of `float` (grey data) or Vec3f holding `rgb`. With `like`, the grid continues it: same
/// name, class and metadata, and (when `patch`) its tree, with only the changed voxels rewritten.
/// `activeIn`: see writeDense.
openvdb::GridBase::Ptr makeRoleGrid(Role role, const std::vector<float>& rgb, bool asFloat,
                                    const openvdb::GridBase::ConstPtr& like, bool patch, const openvdb::Coord& origin,
                                    Int3 dims, const openvdb::math::Transform::Ptr& xf, const std::vector<float>* activeIn = nullptr) {
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
        writeDense(*grid, origin, dims, rgb, activeIn);
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
    const Int3 dims = volume.dims();
    const bool grey = Volume::isGrey(rgb);
    if (like && sameIndexSpace) {
        const auto& reference = *source->roles[kExtinction];
        if (densifyRole(role, like, reference, origin, dims, "") == rgb) return like;  // unchanged: the file's own grid
        const bool wasFloat = like->isType<openvdb::FloatGrid>();
        const bool sameType = wasFloat ? grey : true;
        if (sameType && like->transform() == reference.transform())
            return makeRoleGrid(role, rgb, wasFloat, like, /*patch=*/true, origin, dims, xf);
    }
    // Made from scratch; a float grid of the file stays float while the data stays grey.
    const bool asFloat = like ? (like->isType<openvdb::FloatGrid>() && grey)
                              : (role == kRefractiveIndex || (role == kExtinction && grey));
    // Albedo's voxels inside the medium are active even where they are the background's 1:
    // Blender's Cycles reads an inactive voxel as 0 (a white cloud would render black there).
    return makeRoleGrid(role, rgb, asFloat, like, /*patch=*/false, origin, dims, xf, role == kAlbedo ? &volume.extinction() : nullptr);
}

}  // namespace

void saveVdb(const std::string& path, const Volume& volume) {
    initOpenVdb();
    volume.validate(VolumeLimits{std::numeric_limits<int64_t>::max(), std::numeric_limits<int>::max()});
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
