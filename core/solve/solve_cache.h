#pragma once
/// \file solve_cache.h
/// What a solve leaves for the next one in the same session (issue #12: re-solve after a stroke).
/// Each view's rows of W and its bound renders (reach.h) depend only on the camera, the parts of
/// the volume the unknowns are not, the lighting and the solve settings — a stroke changes one
/// view's target and a solve changes only the unknowns, so the next solve finds all the other
/// views' parts here. Entries are kept under keys that name everything they depend on (the
/// *Key functions), bounded by bytes, least recently used dropped first; a solve holds what it
/// uses, so dropping never frees an entry in use. GL thread only (the rows are GL buffers).

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/solve/reach.h"
#include "core/scene/solve_options.h"
#include "core/solve/sparse_rows.h"
#include "core/volume/volume.h"

namespace volstyle::core {

/// What a finished solve asked for and where it ended (SolveOptions::localResolve): per pixel the
/// observations and raw weights (4 floats each, as the solver builds them), and a hash of the
/// unknowns' grids in the volume it returned. The next solve with the same settings compares.
struct LastSolve {
    std::vector<float> observations, weights;
    uint64_t resultHash = 0;
};

class SolveCache {
public:
    explicit SolveCache(size_t budgetBytes = size_t(1) << 30) : m_budget(budgetBytes) {}

    std::shared_ptr<const SparseRows> findRows(const std::string& key) { return find<SparseRows>(key); }
    void putRows(const std::string& key, std::shared_ptr<const SparseRows> rows);
    std::shared_ptr<const ViewRenders> findRenders(const std::string& key) { return find<ViewRenders>(key); }
    void putRenders(const std::string& key, std::shared_ptr<const ViewRenders> renders);
    std::shared_ptr<const LastSolve> findLastSolve(const std::string& key) { return find<LastSolve>(key); }
    void putLastSolve(const std::string& key, std::shared_ptr<const LastSolve> last);

    size_t bytes() const { return m_bytes; }
    size_t budget() const { return m_budget; }
    size_t entries() const { return m_entries.size(); }
    size_t hits() const { return m_hits; }
    size_t misses() const { return m_misses; }
    void clear();

private:
    struct Entry {
        std::shared_ptr<const void> value;
        size_t bytes = 0;
        uint64_t lastUsed = 0;
    };
    template <typename T>
    std::shared_ptr<const T> find(const std::string& key) {
        auto it = m_entries.find(key);
        if (it == m_entries.end()) {
            ++m_misses;
            return nullptr;
        }
        ++m_hits;
        it->second.lastUsed = ++m_clock;
        return std::static_pointer_cast<const T>(it->second.value);
    }
    void put(const std::string& key, std::shared_ptr<const void> value, size_t bytes);

    size_t m_budget, m_bytes = 0, m_hits = 0, m_misses = 0;
    uint64_t m_clock = 0;
    std::unordered_map<std::string, Entry> m_entries;
};

/// The key of one view's rows: the extinction (and, for albedo, the lighting), the camera, the
/// unknowns' grid and basis, the march, and which of the view's pixels have weight.
std::string rowsKey(const Volume& volume, const Lighting& lighting, const SolveOptions& options, Int3 unknownDims,
                    const Camera& camera, int channels, const std::vector<float>& sqrtWeights, size_t firstPixel);
/// The key of one view's bound renders: every grid but the unknowns' own (a solve changes only
/// those, and the fixed part it needs excludes them), the lighting, the camera, the march.
std::string rendersKey(const Volume& volume, const Lighting& lighting, const SolveOptions& options, const Camera& camera,
                       bool withAlbedoOne);

/// The key of the last solve over these views: everything a solve's optimum depends on but the
/// targets, the weights and the unknowns' values (the settings, every other grid, the lighting,
/// the cameras in order).
std::string lastSolveKey(const Volume& volume, const Lighting& lighting, const SolveOptions& options, Int3 unknownDims,
                         const std::vector<SolveView>& views);
/// A hash of the grids `unknown` solves for (emission, albedo, both or extinction) in `volume`.
uint64_t unknownsHash(const Volume& volume, Unknown unknown);

}  // namespace volstyle::core
