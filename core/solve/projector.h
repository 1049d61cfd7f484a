#pragma once
/// \file projector.h
/// The matrix-free operator W of the painting solver and its adjoint (TVCG Sec. 4.2, 5.1), both
/// from project.comp: `forward` renders an unknown field into every view's pixels (W a);
/// `adjoint` scatters per-pixel residuals back into the unknown grid along the same rays with the
/// same weights (Wᵀ r). GL thread only.

#include <functional>
#include <memory>
#include <vector>

#include "core/base/work_budget.h"
#include "core/gpu/gpu_device.h"
#include "core/render/gpu_volume.h"
#include "core/render/march_setup.h"
#include "core/solve/gpu_vector.h"
#include "core/scene/solve_types.h"
#include "core/solve/sparse_rows.h"

namespace volstyle::core {

struct ProjectorStats {
    double forwardMs = 0;
    double adjointMs = 0;
    int forwardCalls = 0;
    int adjointCalls = 0;
    double cacheMs = 0;       ///< writing the cached rows (cacheRows)
    size_t cacheBytes = 0;    ///< GPU memory they take
    size_t cachedViews = 0;   ///< views whose W and Wᵀ run from them
    size_t cachedEntries = 0;
    int lightVolumes = 0;     ///< light-depth volumes its views' set-up computed (only albedo's W is lit)
};

class Projector {
public:
    /// `unknownDims`: the unknown grid (the extinction grid's dims or coarser, same box).
    Projector(GpuDevice& device, GpuVolume& volume, const Lighting& lighting, Unknown unknown,
              BasisType basis, Int3 unknownDims, double stepVoxels, bool exactTraversal = false);

    /// A sparse volume's unknowns: the stored voxels of `bricks`, a sparse grid of unknownDims (the
    /// volume's own bricks, or coarser ones over the same box). Required before addView for a
    /// sparse volume.
    void useSparseUnknowns(const BrickLayout& bricks);

    /// Adds a view; its pixels follow those of the views added before (row-major, top row first).
    /// The view holds its light-depth volumes for the projector's lifetime.
    void addView(const Camera& camera);
    size_t viewCount() const { return m_views.size(); }
    size_t pixelCount() const { return m_pixelCount; }
    Range viewRange(size_t view) const { return {m_views[view].offset, size_t(m_views[view].camera.width) * m_views[view].camera.height}; }
    /// Unknowns per block: the unknown grid's voxels, or a sparse grid's stored voxels.
    size_t cellCount() const { return m_sparseUnknowns ? m_sparseUnknowns->cells : size_t(m_unknownDims.volume()); }
    /// Unknown elements: cellCount(), times 2 for emission + albedo.
    size_t elementCount() const { return cellCount() * (m_unknown == Unknown::EmissionAlbedo ? 2 : 1); }
    Int3 unknownDims() const { return m_unknownDims; }
    Unknown unknown() const { return m_unknown; }

    void forward(const GpuVector& a, GpuVector& pixels);   ///< pixels = W a
    void adjoint(const GpuVector& pixels, GpuVector& a);   ///< a = Wᵀ pixels
    /// pixels = W c by the columns of the cached rows, reading only the columns where c ≠ 0 (the
    /// unknowns a bound clamped): cheap where c is sparse. Needs canForwardByColumns().
    void forwardByColumns(const GpuVector& c, GpuVector& pixels);
    bool canForwardByColumns() const { return m_merged || (allCached() && m_views.size() == 1); }
    /// One view's rows: its pixels of `pixels` = W_v a (the other views' pixels keep theirs), and
    /// a = W_vᵀ (its pixels of `pixels`). For methods that sweep the views (SART, solver_baselines.cpp).
    void forwardView(size_t view, const GpuVector& a, GpuVector& pixels);
    void adjointView(size_t view, const GpuVector& pixels, GpuVector& a);
    const ProjectorStats& stats() const { return m_stats; }
    /// Scatter with GL_NV_shader_atomic_float (default where the context has it) or with the
    /// compare-and-swap fallback; tests cover both.
    void setUseFloatAtomics(bool use);
    /// The rows' passes (cacheRows) in chunks that stop as `budget` says (kept by pointer; null,
    /// the default: a view at a time). Work ahead (solve_prefetch.h) yields to requests so.
    void setBudget(const WorkBudget* budget) { m_budget = budget; }
    /// Writes each view's rows of W and their transpose (sparse_rows.h) while they fit in
    /// `budgetBytes` and in one storage block; W and Wᵀ of those views then gather from them and
    /// the others stay matrix-free. Valid while the extinction and the lighting stay as they
    /// were (a solve never changes them). `channels`: weightChannels() of the problem. With
    /// `pixelMask` (the solver's √weights), pixels whose mask is 0 get empty rows: W from the
    /// cache is then 0 there, which the solver multiplies by 0 anyway.
    void cacheRows(size_t budgetBytes, int channels, const GpuVector* pixelMask = nullptr);
    /// Where cacheRows() places the columns (Wᵀ's entries): by the fill pass itself with atomics
    /// (GPUs), or transposed from the rows on the host (the default on a CPU rasterizer, where the
    /// atomics' scattered writes cost more than a counting sort). Either gives the same columns,
    /// each in another order.
    void setColumnsOnHost(bool onHost) { m_columnsOnHost = onHost; }
    /// Whether W and Wᵀ from rows the host can map run on the host (host_products.h; the default
    /// on a CPU rasterizer) or in sparse_project.comp. Either gives the same sums in the same order.
    void setProductsOnHost(bool onHost) { m_productsOnHost = onHost; }
    /// Whether cacheRows() merges the views' rows into one (mergeRows): the default on a GPU, where
    /// W and Wᵀ then take one dispatch instead of one per view. The host's products gather view by
    /// view at the same cost, so a CPU rasterizer keeps each view's rows and skips the merge's copy
    /// of every entry ((b): 2.38 -> 2.12 s of rows, docs/BENCHMARKS.md).
    void setMergeViews(bool merge) { m_mergeViews = merge; }
    bool mergesViews() const { return m_mergeViews; }
    /// Once rows are merged, each view's own rows stay beside them only while both together take
    /// at most `bytes` (default 0: never). Kept, a later solve whose one view changed (a stroke)
    /// rebuilds that view's rows alone; dropped, memory is halved and the solver's cache holds a
    /// problem twice as large (issue #40).
    void keepViewRowsWithin(size_t bytes) { m_keepViewRowsBytes = bytes; }
    bool allCached() const { return m_stats.cachedViews == m_views.size(); }
    /// A view's rows, from an earlier solve (SolveCache) or for one: rows written for this view's
    /// camera, unknowns and pixel mask. Not once rows are merged.
    void adoptRows(size_t view, std::shared_ptr<const SparseRows> rows);
    /// A view's own rows; null once merged (the merged rows hold them: mergedRows(), viewRange()).
    std::shared_ptr<const SparseRows> rowsOf(size_t view) const { return m_views[view].rows; }
    /// Whether W and Wᵀ run as one gather over every view's rows at once (mergeRows).
    bool merged() const { return m_merged != nullptr; }
    /// Those rows, to keep for a later solve (SolveCache), and to take from one: rows merged from
    /// exactly this projector's views' rows, in order. A view is the range viewRange() of them;
    /// its own rows are dropped once merged unless keepViewRowsWithin() allows both.
    std::shared_ptr<const SparseRows> mergedRows() const { return m_merged; }
    void adoptMergedRows(std::shared_ptr<const SparseRows> rows);
    /// Marks (sparseMark) through the cached rows of every view: the unknowns the rows of `list`'s
    /// pixels reach (columns = false), or the pixels the columns of `list`'s elements reach.
    void markThroughRows(bool columns, const Support& list, GpuVector& marks) const;
    /// With every view cached: W computes only these pixels (others keep their values) and Wᵀ
    /// only these elements (others are 0). Null: all.
    void setSupports(std::shared_ptr<const Support> pixels, std::shared_ptr<const Support> elements);

private:
    struct View {
        Camera camera;
        MarchSetup setup;
        size_t offset;
        std::shared_ptr<const SparseRows> rows;  ///< null: matrix-free
    };
    /// project.comp over one view: the shader with the projector's defines and the view's march bound.
    void useProgram(const View& v, gl::ShaderBuilder& builder);
    void dispatchView(const View& v);
    /// Matrix-free W or Wᵀ over the views without cached rows (with `only`: that view alone).
    void dispatch(bool adjoint, const GpuVector& unknowns, const GpuVector& pixels, const View* only = nullptr);
    void timed(bool adjoint, const std::function<void()>& work);
    /// W a from `rows` (a view's own, or `view`'s range of merged rows) into `pixels` from
    /// `pixelOffset`, and a += Wᵀ r from their columns (reading `pixelsRead` of merged rows' pixels
    /// only): on the host where it can map them (setProductsOnHost), else by sparse_project.comp.
    void gatherRows(const SparseRows& rows, Range view, size_t pixelOffset, const GpuVector& a, GpuVector& pixels, const Support* only);
    void gatherColumns(const SparseRows& rows, size_t pixelOffset, Range pixelsRead, const GpuVector& pixels, GpuVector& a,
                       const Support* only);
    /// Counts, then writes, one view's rows and columns; null when past the budget.
    std::unique_ptr<SparseRows> buildRows(const View& v, size_t budgetBytes, int channels, const GpuVector* pixelMask);
    /// With every view cached: one row/column structure over all of them (rows concatenated,
    /// each element's columns appended view after view: by sparse_merge.comp, or on a CPU rasterizer by the host), so W and Wᵀ are one
    /// dispatch each instead of one per view. Skipped (per-view gathers stay) past `budgetBytes`
    /// or one storage block.
    void mergeRows(size_t budgetBytes);
    /// The merged columns by sparse_merge.comp (host_columns.h merges them on a CPU rasterizer).
    void mergeColumnsOnDevice(SparseRows& merged);
    /// Frees each view's own rows once merged rows hold them.
    void dropViewRows();

    GpuDevice& m_device;
    GpuVolume& m_volume;
    Lighting m_lighting;
    Unknown m_unknown;
    BasisType m_basis;
    Int3 m_unknownDims;
    std::shared_ptr<const SparseCells> m_sparseUnknowns;  ///< a sparse volume's unknown grid (else null)
    double m_step;
    bool m_exactTraversal;
    std::vector<View> m_views;
    size_t m_pixelCount = 0;
    ProjectorStats m_stats;
    bool m_useFloatAtomics = false;
    const WorkBudget* m_budget = nullptr;
    std::shared_ptr<const Support> m_pixelSupport, m_elementSupport;
    std::shared_ptr<const SparseRows> m_merged;  ///< every view's rows at once (mergeRows); null: per view
    bool m_columnsOnHost = false;                ///< setColumnsOnHost (constructor: a CPU rasterizer)
    bool m_productsOnHost = false;               ///< setProductsOnHost (constructor: a CPU rasterizer)
    bool m_mergeViews = true;                    ///< setMergeViews (constructor: not on a CPU rasterizer)
    size_t m_keepViewRowsBytes = 0;              ///< keepViewRowsWithin
};

}  // namespace volstyle::core
