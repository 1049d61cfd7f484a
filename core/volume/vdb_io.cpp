// OpenVDB read/write. The only translation unit that includes OpenVDB headers.

#include "core/volume/vdb_io.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Prune.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

namespace fs = std::filesystem;

void initOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

/// OpenVDB matrices act on row vectors (p' = p·M); ours on column vectors: transpose.
Mat4 fromVdb(const openvdb::math::Mat4d& m) {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(i, j) = m(j, i);
    return r;
}

openvdb::math::Mat4d toVdb(const Mat4& m) {
    openvdb::math::Mat4d r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r(j, i) = m(i, j);
    return r;
}

Mat4 worldFromIndexOf(const openvdb::GridBase& grid, const std::string& path) {
    const openvdb::math::Transform& xf = grid.transform();
    if (!xf.isLinear()) {
        throw InvalidArgument("loadVdb(): grid '" + grid.getName() + "' in '" + path +
                              "' has a non-linear (frustum) transform; only linear transforms are supported");
    }
    return fromVdb(xf.baseMap()->getAffineMap()->getMat4());
}

std::string gridNames(const openvdb::GridPtrVec& grids) {
    std::string s;
    for (const auto& g : grids) s += (s.empty() ? "" : ", ") + g->getName();
    return s.empty() ? "(none)" : s;
}

openvdb::GridBase::Ptr findGrid(const openvdb::GridPtrVec& grids, const std::string& name) {
    for (const auto& g : grids)
        if (g->getName() == name) return g;
    return nullptr;
}

/// Fills a dense RGB grid from a float or Vec3f VDB grid, voxel (i,j,k) of the dense grid being
/// index `origin + (i,j,k)` of `reference`. Uses direct lookups when the transforms agree, and
/// trilinear world-space resampling otherwise.
void densify(const openvdb::GridBase::Ptr& grid, const openvdb::GridBase& reference,
             const openvdb::Coord& origin, Int3 dims, std::vector<float>& out,
             const std::string& path) {
    out.assign(size_t(dims.volume()) * 3, 0.0f);
    const bool sameTransform = grid->transform() == reference.transform();
    auto forEachVoxel = [&](auto&& valueAt) {
        size_t n = 0;
        for (int k = 0; k < dims.z; ++k)
            for (int j = 0; j < dims.y; ++j)
                for (int i = 0; i < dims.x; ++i, ++n) {
                    openvdb::Coord ijk = origin + openvdb::Coord(i, j, k);
                    openvdb::Vec3s v = valueAt(ijk);
                    out[3 * n] = v[0], out[3 * n + 1] = v[1], out[3 * n + 2] = v[2];
                }
    };
    auto fill = [&](auto typedGrid) {
        using GridT = typename decltype(typedGrid)::element_type;
        auto acc = typedGrid->getConstAccessor();
        openvdb::tools::GridSampler<typename GridT::ConstAccessor, openvdb::tools::BoxSampler> sampler(
            acc, typedGrid->transform());
        forEachVoxel([&](const openvdb::Coord& ijk) {
            typename GridT::ValueType v = sameTransform
                ? acc.getValue(ijk)
                : sampler.wsSample(reference.transform().indexToWorld(ijk));
            return openvdb::Vec3s(v);
        });
    };
    if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) {
        fill(f);
    } else if (auto v = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid)) {
        fill(v);
    } else {
        throw InvalidArgument("loadVdb(): grid '" + grid->getName() + "' in '" + path + "' has type '" +
                              grid->valueType() + "'; expected float or vec3s");
    }
}

openvdb::GridPtrVecPtr readAllGrids(const std::string& path) {
    initOpenVdb();
    if (!fs::exists(path)) throw IoError("loadVdb(): no such file '" + path + "'");
    // OpenVDB keeps reading a truncated file with garbage sizes and may allocate gigabytes. A
    // stream that throws on any short read stops it at the first missing byte instead.
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("loadVdb(): cannot open '" + path + "'");
    in.exceptions(std::ios::failbit | std::ios::badbit);
    try {
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        return stream.getGrids();
    } catch (const std::ios_base::failure&) {
        throw IoError("loadVdb(): '" + path + "' is truncated (it ends before its grids do)");
    } catch (const openvdb::Exception& e) {
        throw IoError("loadVdb(): '" + path + "' is not a readable OpenVDB file (corrupt or truncated): " + e.what());
    } catch (const std::bad_alloc&) {
        // Damaged block sizes make OpenVDB ask for more memory than exists (found by fuzzing).
        throw IoError("loadVdb(): '" + path + "' is damaged: reading it asks for more memory than its grids can need");
    } catch (const std::exception& e) {
        throw IoError("loadVdb(): '" + path + "' could not be read: " + e.what());
    }
}

}  // namespace

Volume loadVdb(const std::string& path, const VolumeLimits& limits) {
    auto grids = readAllGrids(path);
    auto extinction = findGrid(*grids, "extinction");
    if (!extinction) extinction = findGrid(*grids, "density");
    if (!extinction) {
        throw InvalidArgument("loadVdb(): neither an 'extinction' nor a 'density' grid in '" + path +
                              "'; grids present: " + gridNames(*grids));
    }
    const openvdb::CoordBBox box = extinction->evalActiveVoxelBoundingBox();
    if (box.empty()) {
        throw InvalidArgument("loadVdb(): grid '" + extinction->getName() + "' in '" + path +
                              "' has no active voxels");
    }
    // The box's extent in 64 bits: voxels at ±2e9 overflow OpenVDB's 32-bit Coord::dim().
    int64_t extent[3];
    for (int a = 0; a < 3; ++a) extent[a] = int64_t(box.max()[a]) - int64_t(box.min()[a]) + 1;
    const bool sideOver = extent[0] > limits.maxSide || extent[1] > limits.maxSide || extent[2] > limits.maxSide;
    if (sideOver || extent[0] * extent[1] * extent[2] > limits.maxVoxels) {  // sides ≤ 2³², product fits
        std::ostringstream s;
        s << "loadVdb(): the active box of '" << extinction->getName() << "' in '" << path << "' is " << extent[0] << "x"
          << extent[1] << "x" << extent[2] << " voxels, over the limit of " << limits.maxVoxels << " voxels (at most "
          << limits.maxSide << " on a side)";
        throw LimitExceeded(s.str());
    }
    const Int3 dims{int(extent[0]), int(extent[1]), int(extent[2])};

    // Dense voxel (0,0,0) is the box's minimum corner.
    const openvdb::Coord o = box.min();
    Mat4 worldFromIndex = worldFromIndexOf(*extinction, path) * Mat4::translate({double(o.x()), double(o.y()), double(o.z())});
    Volume volume(dims, worldFromIndex);
    densify(extinction, *extinction, o, dims, volume.extinction(), path);
    for (const char* name : {"albedo", "emission"}) {
        if (auto g = findGrid(*grids, name)) {
            worldFromIndexOf(*g, path);  // rejects frustum transforms
            densify(g, *extinction, o, dims, std::string(name) == "albedo" ? volume.albedo() : volume.emission(), path);
        }
    }
    if (auto g = findGrid(*grids, "refractive_index")) {
        std::vector<float> rgb;
        densify(g, *extinction, o, dims, rgb, path);
        std::vector<float> n(volume.voxelCount());
        for (size_t i = 0; i < n.size(); ++i) n[i] = rgb[3 * i] == 0.0f ? 1.0f : rgb[3 * i];  // inactive: vacuum
        volume.refractiveIndex() = std::move(n);
    }
    try {
        volume.validate(limits);
    } catch (const LimitExceeded& e) {
        throw LimitExceeded(std::string(e.what()) + " (in '" + path + "')");
    } catch (const InvalidArgument& e) {
        throw InvalidArgument(std::string(e.what()) + " (in '" + path + "')");
    }
    return volume;
}

namespace {

template <typename GridT, typename Value>
typename GridT::Ptr makeGrid(const Volume& v, const std::string& name, const openvdb::math::Transform::Ptr& xf,
                             Value (*valueAt)(const std::vector<float>&, size_t), const std::vector<float>& data) {
    auto grid = GridT::create();
    grid->setName(name);
    grid->setTransform(xf);
    auto acc = grid->getAccessor();
    const Int3 d = v.dims();
    const auto& ext = v.extinction();
    size_t n = 0;
    for (int k = 0; k < d.z; ++k)
        for (int j = 0; j < d.y; ++j)
            for (int i = 0; i < d.x; ++i, ++n) {
                if (ext[3 * n] == 0.0f && ext[3 * n + 1] == 0.0f && ext[3 * n + 2] == 0.0f) continue;
                acc.setValue(openvdb::Coord(i, j, k), valueAt(data, n));  // an active leaf voxel
            }
    // Drop only inactive background; active constant regions stay voxels (no tiles).
    openvdb::tools::pruneInactive(grid->tree());
    return grid;
}

float greyAt(const std::vector<float>& g, size_t n) { return g[3 * n]; }
openvdb::Vec3s rgbAt(const std::vector<float>& g, size_t n) { return {g[3 * n], g[3 * n + 1], g[3 * n + 2]}; }

bool isGrey(const std::vector<float>& g) {
    for (size_t i = 0; i < g.size(); i += 3)
        if (g[i] != g[i + 1] || g[i] != g[i + 2]) return false;
    return true;
}

}  // namespace

void saveVdb(const std::string& path, const Volume& volume) {
    initOpenVdb();
    volume.validate(VolumeLimits{std::numeric_limits<int64_t>::max(), std::numeric_limits<int>::max()});
    auto xf = openvdb::math::Transform::createLinearTransform(toVdb(volume.worldFromIndex()));
    openvdb::GridPtrVec grids;
    if (isGrey(volume.extinction())) {
        auto g = makeGrid<openvdb::FloatGrid>(volume, "density", xf, greyAt, volume.extinction());
        g->setGridClass(openvdb::GRID_FOG_VOLUME);
        grids.push_back(g);
    } else {
        grids.push_back(makeGrid<openvdb::Vec3SGrid>(volume, "extinction", xf, rgbAt, volume.extinction()));
    }
    if (volume.hasAlbedo())
        grids.push_back(makeGrid<openvdb::Vec3SGrid>(volume, "albedo", xf, rgbAt, volume.albedo()));
    if (volume.hasEmission())
        grids.push_back(makeGrid<openvdb::Vec3SGrid>(volume, "emission", xf, rgbAt, volume.emission()));
    if (volume.refractiveIndex()) {
        std::vector<float> rgb(volume.voxelCount() * 3);
        for (size_t i = 0; i < volume.voxelCount(); ++i) rgb[3 * i] = (*volume.refractiveIndex())[i];
        grids.push_back(makeGrid<openvdb::FloatGrid>(volume, "refractive_index", xf, greyAt, rgb));
    }
    for (auto& g : grids) g->insertMeta("creator", openvdb::StringMetadata("volstyle"));

    // Atomic replace: a crash mid-write never leaves a half-written file under `path`.
    const std::string tmp = path + ".tmp";
    try {
        openvdb::io::File file(tmp);
        file.write(grids);
        file.close();
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError("saveVdb(): cannot write '" + path + "': " + e.what());
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw IoError("saveVdb(): cannot move '" + tmp + "' to '" + path + "': " + ec.message());
}

std::vector<VdbGridInfo> inspectVdb(const std::string& path) {
    auto grids = readAllGrids(path);
    std::vector<VdbGridInfo> out;
    for (const auto& g : *grids) {
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
        if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g)) scan(f);
        else if (auto v = openvdb::gridPtrCast<openvdb::Vec3SGrid>(g)) scan(v);
        if (info.activeVoxels == 0 || lo.x > hi.x) lo = hi = Vec3(0.0f);
        info.minValue = lo, info.maxValue = hi;
        out.push_back(info);
    }
    return out;
}

}  // namespace volstyle::core
