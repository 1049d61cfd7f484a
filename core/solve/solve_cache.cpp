#include "core/solve/solve_cache.h"

#include <fmt/format.h>

#include <algorithm>
#include <string_view>

namespace volstyle::core {
namespace {

size_t hashOf(const void* data, size_t bytes) {
    return std::hash<std::string_view>{}(std::string_view(static_cast<const char*>(data), bytes));
}
size_t hashOf(const std::vector<float>& v) { return hashOf(v.data(), v.size() * sizeof(float)); }

size_t imageBytes(const Image& i) { return i.rgba.size() * sizeof(float); }

std::string boxKey(const Volume& v) {
    std::string key = fmt::format("{}x{}x{}:", v.dims().x, v.dims().y, v.dims().z);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) key += fmt::format("{},", v.worldFromIndex()(r, c));  // shortest round-trip: exact
    return key;
}

std::string gridKey(const Volume& v) {
    std::string key = boxKey(v) + fmt::format(":σ{:x}", hashOf(v.extinction()));
    if (const BrickLayout* b = v.bricks()) key += fmt::format(":bricks{:x}", hashOf(b->slotTable().data(), b->slotTable().size() * 4));
    if (const auto& n = v.refractiveIndex()) key += fmt::format(":n{:x}", hashOf(*n));  // bends every ray: renders and rows alike
    return key;
}

std::string lightingKey(const Lighting& l) {
    std::string key = "light:";
    for (const auto& d : l.lights)
        key += fmt::format("{},{},{}/{},{},{};", d.direction.x, d.direction.y, d.direction.z, d.irradiance.x,
                           d.irradiance.y, d.irradiance.z);
    key += fmt::format("phase{}:{}:bg{},{},{}", int(l.phase.type), l.phase.g, l.background.color.x, l.background.color.y,
                       l.background.color.z);
    if (l.background.environment)  // its content, not its address: a session reloads it
        key += fmt::format(":env{}x{}:{:x}", l.background.environment->width, l.background.environment->height,
                           hashOf(l.background.environment->rgba));
    if (l.background.plate)  // a view's plate (SolveView::lightingFor)
        key += fmt::format(":plate{}x{}:{:x}", l.background.plate->width, l.background.plate->height, hashOf(l.background.plate->rgba));
    if (l.environment.active()) {  // the lobes' radiances as they light the volume (the map's, or given)
        key += fmt::format(":lobes{}:{}:{}:", l.environment.lobes, int(l.environment.domain), l.environment.lightVolumeResolution);
        for (const Vec3d& r : lobeRadiance(l.environment)) key += fmt::format("{},{},{};", r.x, r.y, r.z);
    }
    return key;
}

/// The emission and albedo grids, but those `u` solves for (a solve changes only its own).
std::string otherPropertiesKey(const Volume& v, Unknown u) {
    const bool ownsEmission = u == Unknown::Emission || u == Unknown::EmissionAlbedo;
    const bool ownsAlbedo = u == Unknown::Albedo || u == Unknown::EmissionAlbedo;
    std::string key;
    if (!ownsEmission) key += fmt::format(":e{:x}", v.hasEmission() ? hashOf(v.emission()) : 0);
    if (!ownsAlbedo) key += fmt::format(":a{:x}", v.hasAlbedo() ? hashOf(v.albedo()) : 0);
    return key;
}

std::string marchKey(const SolveOptions& o) { return fmt::format("step{}:{}", o.stepVoxels, o.exactTraversal ? "exact" : "march"); }

}  // namespace

std::string cameraKey(const Camera& c) {
    return fmt::format("cam:{},{},{}:{},{},{}:{},{},{}:{}:{}x{}:{},{}", c.eye.x, c.eye.y, c.eye.z, c.target.x, c.target.y,
                       c.target.z, c.up.x, c.up.y, c.up.z, c.fovYDeg, c.width, c.height, c.nearDist, c.farDist);
}

void SolveCache::putRows(const std::string& key, std::shared_ptr<const SparseRows> rows, double costMs) {
    const size_t bytes = sparseRowsBytes(rows->rows, rows->columns, rows->entries, rows->channels);
    put(key, std::move(rows), bytes, costMs);
}

void SolveCache::putRenders(const std::string& key, std::shared_ptr<const ViewRenders> r, double costMs) {
    const size_t bytes = imageBytes(r->now) + imageBytes(r->noEmission) + imageBytes(r->albedo0) + imageBytes(r->albedo1) +
                         imageBytes(r->neither) + imageBytes(r->background);
    put(key, std::move(r), bytes, costMs);
}

void SolveCache::putLastSolve(const std::string& key, std::shared_ptr<const LastSolve> last, double costMs) {
    const size_t bytes = (last->observations.size() + last->weights.size()) * sizeof(float);
    put(key, std::move(last), bytes, costMs);
}

void SolveCache::put(const std::string& key, std::shared_ptr<const void> value, size_t bytes, double costMs) {
    if (auto it = m_entries.find(key); it != m_entries.end()) {
        m_bytes -= it->second.bytes;
        costMs = std::max(costMs, it->second.costMs);
    }
    Entry& e = m_entries[key] = Entry{std::move(value), bytes, std::max(costMs, 0.0), 0};
    e.priority = priorityOf(e);
    m_bytes += bytes;
    // The entry of least priority goes (the one just put too, when it is worth the least per
    // byte), until the rest fit; one entry always stays.
    while (m_bytes > m_budget && m_entries.size() > 1) {
        auto lowest = std::min_element(m_entries.begin(), m_entries.end(),
                                       [](const auto& a, const auto& b) { return a.second.priority < b.second.priority; });
        m_inflation = lowest->second.priority;
        m_bytes -= lowest->second.bytes;
        m_entries.erase(lowest);
    }
}

void SolveCache::clear() {
    m_entries.clear();
    m_bytes = 0;
}

VolumeKey volumeKeyOf(const Volume& volume, Unknown unknown) {
    // (An extinction solve owns neither emission nor albedo: its "others" are both.)
    return {boxKey(volume), gridKey(volume), otherPropertiesKey(volume, unknown), otherPropertiesKey(volume, Unknown::Extinction)};
}

std::vector<uint8_t> weightedPixels(const std::vector<float>& sqrtWeights, size_t firstPixel, size_t count) {
    std::vector<uint8_t> mask(count);
    for (size_t i = 0; i < count; ++i) {
        const float* w = &sqrtWeights[4 * (firstPixel + i)];
        mask[i] = w[0] > 0 || w[1] > 0 || w[2] > 0;
    }
    return mask;
}

std::string rowsKey(const VolumeKey& volume, const Lighting& lighting, const SolveOptions& options, Int3 unknownDims,
                    const Camera& camera, int channels, const std::vector<uint8_t>& mask) {
    const bool lit = options.unknown == Unknown::Albedo || options.unknown == Unknown::EmissionAlbedo;
    return fmt::format("rows:{}:{}:{}x{}x{}:{}:{}:{}:{}:{}:mask{:x}", int(options.unknown), int(options.basis), unknownDims.x,
                       unknownDims.y, unknownDims.z, channels, marchKey(options),
                       // extinction solves' rows are segment lengths: the grid's box, not its values
                       options.unknown == Unknown::Extinction ? volume.box : volume.grid,
                       lit ? lightingKey(lighting) : "", cameraKey(camera), hashOf(mask.data(), mask.size()));
}

namespace {

/// A view's bound renders under `tag` (the unknowns, or "exact"), with `grids` the hashes of the
/// emission and albedo grids the key names.
std::string rendersKeyOf(const std::string& tag, const std::string& grids, const VolumeKey& volume, const Lighting& lighting,
                         const SolveOptions& options, const Camera& camera, bool withAlbedoOne) {
    return fmt::format("renders:{}:{}:{}:{}:{}", tag, withAlbedoOne ? 1 : 0, marchKey(options), volume.grid, lightingKey(lighting)) + grids +
           ":" + cameraKey(camera);
}

}  // namespace

std::string rendersKey(const VolumeKey& volume, const Lighting& lighting, const SolveOptions& options, const Camera& camera,
                       bool withAlbedoOne) {
    return rendersKeyOf(std::to_string(int(options.unknown)), volume.others, volume, lighting, options, camera, withAlbedoOne);
}

std::string exactRendersKey(const VolumeKey& volume, const Lighting& lighting, const SolveOptions& options, const Camera& camera,
                            bool withAlbedoOne) {
    return rendersKeyOf("exact", volume.all, volume, lighting, options, camera, withAlbedoOne);
}

std::string lastSolveKey(const Volume& volume, const Lighting& lighting, const SolveOptions& options, Int3 unknownDims,
                         const std::vector<SolveView>& views) {
    auto reg = [](const Regularization& r) { return fmt::format("{},{},{}", r.laplacian, r.l2, r.towardOne); };
    std::string key = fmt::format("last:{}:{}x{}x{}:{}:{}:{}:{}:{}:{}:{}", int(options.basis), unknownDims.x, unknownDims.y,
                                  unknownDims.z, reg(options.regularization),
                                  reg(options.regularizationFor(Unknown::Emission)), reg(options.regularizationFor(Unknown::Albedo)),
                                  options.enforceBounds ? 1 : 0, options.useHull ? 1 : 0,
                                  options.mediumRadiance ? fmt::format("{},{},{}", options.mediumRadiance->x, options.mediumRadiance->y,
                                                                       options.mediumRadiance->z)
                                                         : "-",
                                  options.precondition ? 1 : 0);
    // Every grid but the unknowns' own (an extinction solve's result is a new σ), the lighting, the
    // march and the cameras.
    const Unknown u = options.unknown;
    key += fmt::format(":{}:{}:{}:{}", int(u), marchKey(options), boxKey(volume), lightingKey(lighting));
    if (u != Unknown::Extinction) key += fmt::format(":σ{:x}", hashOf(volume.extinction()));
    key += otherPropertiesKey(volume, u);
    for (const SolveView& v : views) key += "|" + cameraKey(v.camera);
    return key;
}

uint64_t unknownsHash(const Volume& volume, Unknown unknown) {
    auto grid = [](const std::vector<float>& g) { return g.empty() ? uint64_t(0) : uint64_t(hashOf(g)); };
    switch (unknown) {
        case Unknown::Emission: return grid(volume.emission());
        case Unknown::Albedo: return grid(volume.albedo());
        case Unknown::EmissionAlbedo: return grid(volume.emission()) * 1000003u ^ grid(volume.albedo());
        default: return grid(volume.extinction());
    }
}

}  // namespace volstyle::core
