#pragma once
/// \file solve_cache.h
/// What a solve leaves for the next one in the same session (issue #12: re-solve after a stroke).
/// Each view's rows of W and its bound renders (reach.h) depend only on the camera, the parts of
/// the volume the unknowns are not, the lighting and the solve settings — a stroke changes one
/// view's target and a solve changes only the unknowns, so the next solve finds all the other
/// views' parts here. Entries are kept under keys that name everything they depend on (the
/// *Key functions), bounded by bytes; a solve holds what it uses, so dropping never frees an entry
/// in use. GL thread only (the rows are GL buffers).
///
/// What goes first when the bytes are over the budget weighs what an entry saves against what it
/// holds (GreedyDual-Size, Cao & Irani 1997): each entry's priority is the clock L plus the
/// milliseconds it took to make per byte it holds; the lowest goes and L becomes its priority, a
/// hit raises an entry to L + its cost per byte again. Recency still counts (L only grows), but a
/// view's renders (7 MiB that took 0.9 s) outlive a view's rows (95 MiB that took 0.65 s) (issue
/// #40: the 10-view problem (c) rendered every view again after least-recently-used dropped them).

#include <algorithm>
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

    /// `costMs`: what making the entry took (what a miss would cost again). Put again under its
    /// key, an entry keeps the larger of its costs (a hit's put costs nothing to make).
    std::shared_ptr<const SparseRows> findRows(const std::string& key) { return find<SparseRows>(key); }
    void putRows(const std::string& key, std::shared_ptr<const SparseRows> rows, double costMs);
    std::shared_ptr<const ViewRenders> findRenders(const std::string& key) { return find<ViewRenders>(key); }
    void putRenders(const std::string& key, std::shared_ptr<const ViewRenders> renders, double costMs);
    std::shared_ptr<const LastSolve> findLastSolve(const std::string& key) { return find<LastSolve>(key); }
    void putLastSolve(const std::string& key, std::shared_ptr<const LastSolve> last, double costMs);

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
        double costMs = 0;
        double priority = 0;  ///< GreedyDual-Size: m_inflation when last made or hit + costMs per byte
    };
    template <typename T>
    std::shared_ptr<const T> find(const std::string& key) {
        auto it = m_entries.find(key);
        if (it == m_entries.end()) {
            ++m_misses;
            return nullptr;
        }
        ++m_hits;
        it->second.priority = priorityOf(it->second);
        return std::static_pointer_cast<const T>(it->second.value);
    }
    double priorityOf(const Entry& e) const { return m_inflation + e.costMs / double(std::max<size_t>(e.bytes, 1)); }
    void put(const std::string& key, std::shared_ptr<const void> value, size_t bytes, double costMs);

    size_t m_budget, m_bytes = 0, m_hits = 0, m_misses = 0;
    double m_inflation = 0;  ///< GreedyDual-Size's L: the priority of the entry dropped last
    std::unordered_map<std::string, Entry> m_entries;
};

/// What the keys below take from a volume: its box, its extinction (and brick layout), and the
/// grids `unknown` does not solve for. Hashed once per solve, not once per view: (c)'s ten views
/// hashed a 128³ volume's 25 MB grids twenty times, most of its next solve's 1.8 s of "rows".
struct VolumeKey {
    std::string box, grid, others;
    std::string all;  ///< every grid's hash, the unknowns' too: a render of exactly this volume (exactRendersKey)
};
VolumeKey volumeKeyOf(const Volume& volume, Unknown unknown);

/// A camera's every field, exactly (shortest round-trip decimals).
std::string cameraKey(const Camera& camera);

/// Which of a view's `count` pixels, from `firstPixel` of the solver's square-root weights (4 per
/// pixel), have weight: 1, or 0 where no channel has.
std::vector<uint8_t> weightedPixels(const std::vector<float>& sqrtWeights, size_t firstPixel, size_t count);
/// The key of one view's rows: the extinction (and, for albedo, the lighting), the camera, the
/// unknowns' grid and basis, the march, and which of the view's pixels have weight (`mask`).
std::string rowsKey(const VolumeKey& volume, const Lighting& lighting, const SolveOptions& options, Int3 unknownDims,
                    const Camera& camera, int channels, const std::vector<uint8_t>& mask);
/// The key of one view's bound renders: every grid but the unknowns' own (a solve changes only
/// those, and the fixed part it needs excludes them), the lighting, the camera, the march.
std::string rendersKey(const VolumeKey& volume, const Lighting& lighting, const SolveOptions& options, const Camera& camera,
                       bool withAlbedoOne);

/// The key of a view's bound renders of exactly this volume, whatever the unknowns: what the
/// server renders ahead of a solve (solve_prefetch.h) before it knows them. A solve that misses
/// its own key looks here next.
std::string exactRendersKey(const VolumeKey& volume, const Lighting& lighting, const SolveOptions& options, const Camera& camera,
                            bool withAlbedoOne);

/// The key of the last solve over these views: everything a solve's optimum depends on but the
/// targets, the weights and the unknowns' values (the settings, every other grid, the lighting,
/// the cameras in order).
std::string lastSolveKey(const Volume& volume, const Lighting& lighting, const SolveOptions& options, Int3 unknownDims,
                         const std::vector<SolveView>& views);
/// A hash of the grids `unknown` solves for (emission, albedo, both or extinction) in `volume`.
uint64_t unknownsHash(const Volume& volume, Unknown unknown);

}  // namespace volstyle::core
