#include "core/solve/projector.h"

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/render/chunked_dispatch.h"
#include "core/solve/host_columns.h"
#include "core/solve/host_products.h"
#include "core/shaders/layout.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdint>

namespace volstyle::core {

/// Rays stop once every channel's transmittance is below this: forward and adjoint use the same
/// cut-off, so they stay exact transposes; what it drops is below 1e-8 of a pixel.
constexpr float kProjectorTermination = 1e-8f;

Projector::Projector(GpuDevice& device, GpuVolume& volume, const Lighting& lighting, Unknown unknown,
                     BasisType basis, Int3 unknownDims, double stepVoxels, bool exactTraversal)
    : m_device(device), m_volume(volume), m_lighting(lighting), m_unknown(unknown), m_basis(basis),
      m_unknownDims(unknownDims), m_step(stepVoxels), m_exactTraversal(exactTraversal) {
    if (unknownDims.x < 1 || unknownDims.y < 1 || unknownDims.z < 1)
        throw InvalidArgument("Projector: the unknown grid must have at least one voxel");
    m_columnsOnHost = device.capabilities().isSoftware;
    m_productsOnHost = solverKernelsOnHost(device);
    m_mergeViews = !m_productsOnHost;
    // Only albedo's weights hold L_scat: the others need no light-depth volumes, for the lights or
    // the environment (extinction: log-space tomography; emission: T · opacity alone). Issue #40:
    // an emission solve of 128³ under three suns computed three such volumes here for nothing.
    if (unknown == Unknown::Extinction || unknown == Unknown::Emission) {
        m_lighting.lights.clear();
        m_lighting.environment = EnvironmentLight{};
    }
    m_useFloatAtomics = device.capabilities().hasFloatAtomics;
}

void Projector::setUseFloatAtomics(bool use) {
    if (use && !m_device.capabilities().hasFloatAtomics)
        throw InvalidArgument("Projector: this GL context has no GL_NV_shader_atomic_float");
    m_useFloatAtomics = use;
}

void Projector::useSparseUnknowns(const BrickLayout& bricks) {
    VOLSTYLE_CHECK(m_views.size(), ==, size_t(0));
    if (!(bricks.dims() == m_unknownDims)) throw InternalError("Projector: the unknown bricks cover another grid");
    m_sparseUnknowns = std::make_shared<const SparseCells>(bricks);
}

void Projector::addView(const Camera& camera) {
    camera.validate();
    if (m_volume.isSparse() && !m_sparseUnknowns) throw InternalError("Projector: a sparse volume needs its unknown bricks (useSparseUnknowns)");
    RenderSettings settings;
    settings.stepVoxels = m_step;
    settings.exactTraversal = m_exactTraversal;
    RenderStats stats;
    View view{camera, prepareMarch(m_device, m_volume, camera, m_lighting, settings, stats, m_budget ? *m_budget : WorkBudget()), m_pixelCount,
               nullptr};
    m_stats.lightVolumes += stats.lightVolumesRecomputed;
    const Int3 n = m_volume.dims();
    layout::MarchParams& p = view.setup.params;
    p.unknownDims = {m_unknownDims.x, m_unknownDims.y, m_unknownDims.z, 0};
    p.unknownScale = {float(m_unknownDims.x) / float(n.x), float(m_unknownDims.y) / float(n.y),
                      float(m_unknownDims.z) / float(n.z), 0};
    const Int3 o = m_sparseUnknowns ? m_sparseUnknowns->offset : Int3{};
    p.unknownLayout = {int(cellCount()), o.x, o.y, o.z};
    p.viewPixels = {int(m_pixelCount), 0, 0, 0};
    p.projectorCutoff = {kProjectorTermination, 0, 0, 0};
    m_pixelCount += size_t(camera.width) * camera.height;
    m_views.push_back(std::move(view));
}

void Projector::useProgram(const View& v, gl::ShaderBuilder& builder) {
    const bool needsLight = m_unknown == Unknown::Albedo || m_unknown == Unknown::EmissionAlbedo;
    builder.define("VOLSTYLE_UNKNOWN", int(m_unknown))
        .define("VOLSTYLE_BASIS", int(m_basis))
        .define("VOLSTYLE_NUM_LIGHTS", needsLight ? (long long)v.setup.lightDepth.size() : 0)
        .define("VOLSTYLE_HAS_LOBES", needsLight && v.setup.lobes ? 1 : 0)
        .define("VOLSTYLE_SKIP_EMPTY", 1)
        .define("VOLSTYLE_EXACT_TRAVERSAL", m_exactTraversal ? 1 : 0);
    if (v.setup.paths) builder.define("VOLSTYLE_CURVED", 1);  // the view's refracted paths, traced once in addView
    glUseProgram(m_device.program(forStorage(builder, m_volume)).id());
    bindMarch(m_device, m_volume, v.setup);
    if (m_sparseUnknowns) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingUnknownSlots, m_sparseUnknowns->slotOfBrick.id());
}

void Projector::dispatchView(const View& v) {
    if (m_budget && m_budget->bounded())  // in chunks that can stop (work ahead, solve_prefetch.h)
        return dispatchChunked(m_device, v.setup.params, {v.camera.width, v.camera.height, 1}, DispatchShape::Image, *m_budget, "rows of W");
    const int g = layout::kWorkgroup2D;
    glDispatchCompute(GLuint((v.camera.width + g - 1) / g), GLuint((v.camera.height + g - 1) / g), 1);
}

void Projector::dispatch(bool adjoint, const GpuVector& unknowns, const GpuVector& pixels, const View* only) {
    VOLSTYLE_CHECK(unknowns.size(), ==, elementCount());
    VOLSTYLE_CHECK(pixels.size(), ==, m_pixelCount);
    for (const View& v : m_views) {
        if (v.rows || (only && only != &v)) continue;
        gl::ShaderBuilder builder("project.comp");
        builder.define("VOLSTYLE_ADJOINT", adjoint ? 1 : 0);
        if (adjoint && m_useFloatAtomics) {
            builder.define("VOLSTYLE_HAS_FLOAT_ATOMICS", 1).extension("GL_NV_shader_atomic_float");
        }
        useProgram(v, builder);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingUnknown, unknowns.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, adjoint ? layout::kBindingResidual : layout::kBindingImageOut,
                         pixels.id());
        dispatchView(v);
    }
    gl::barrierAfterComputeWrites();
}

namespace {

gl::Buffer zeroedBuffer(size_t bytes, const std::string& label, GLbitfield flags = GL_DYNAMIC_STORAGE_BIT) {
    gl::Buffer b = gl::createBuffer(std::max<size_t>(bytes, 4), nullptr, flags, label);
    const GLuint zero = 0;
    glClearNamedBufferData(b.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    return b;
}

}  // namespace

std::unique_ptr<SparseRows> Projector::buildRows(const View& v, size_t budgetBytes, int channels, const GpuVector* pixelMask) {
    const auto t0 = Clock::now();
    auto r = std::make_unique<SparseRows>();
    r->rows = size_t(v.camera.width) * v.camera.height;
    r->columns = elementCount();
    r->channels = channels;
    const bool hostColumns = m_columnsOnHost;
    r->hostMapped = hostColumns;
    const GLbitfield storage = hostColumns ? kHostMappedStorage : GL_DYNAMIC_STORAGE_BIT;
    r->rowStart = zeroedBuffer(4 * (r->rows + 1), "rows-start", storage);
    r->colStart = zeroedBuffer(4 * (r->columns + 1), "columns-start", storage);
    auto bindStarts = [&] {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowStart, r->rowStart.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColStart, r->colStart.id());
        if (pixelMask) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowMask, pixelMask->id());
    };
    const int masked = pixelMask ? 1 : 0;
    // Pass 1: entries per row (written by each ray) and, on a GPU, per column (counted with
    // atomics; on a CPU rasterizer the host counts them while it transposes: bench/solver_race (b)'s
    // rows went from 3.6 to 3.2–3.4 s, docs/BENCHMARKS.md).
    gl::ShaderBuilder count("project.comp");
    count.define("VOLSTYLE_ROWS", VOLSTYLE_ROWS_COUNT).define("VOLSTYLE_ROW_CHANNELS", channels).define("VOLSTYLE_ROW_MASK", masked);
    count.define("VOLSTYLE_ROW_COLUMNS", hostColumns ? 0 : 1);
    useProgram(v, count);
    bindStarts();
    dispatchView(v);
    gl::barrierAfterComputeWrites();
    std::vector<uint32_t> rowStart(r->rows), colStart(hostColumns ? 0 : r->columns);
    glGetNamedBufferSubData(r->rowStart.id(), 0, GLsizeiptr(4 * r->rows), rowStart.data());
    if (!hostColumns) glGetNamedBufferSubData(r->colStart.id(), 0, GLsizeiptr(4 * r->columns), colStart.data());
    const uint64_t entries = exclusiveScan(rowStart);
    if (!hostColumns) VOLSTYLE_CHECK(exclusiveScan(colStart), ==, entries);
    const size_t weightBytes = entries * 4 * size_t(channels);
    if (entries >= 0xffffffffu || sparseRowsBytes(r->rows, r->columns, entries, channels) > budgetBytes ||
        (long long)weightBytes > m_device.capabilities().maxStorageBlockBytes)
        return nullptr;
    r->entries = entries;
    gl::writeBuffer(r->rowStart, 0, 4 * rowStart.size(), rowStart.data());
    if (!hostColumns) gl::writeBuffer(r->colStart, 0, 4 * colStart.size(), colStart.data());
    // Zeroed: a slot a ray left unfilled (fewer entries than counted) is element 0 with weight 0.
    r->rowIndex = zeroedBuffer(4 * entries, "rows-index", storage);
    r->rowWeight = zeroedBuffer(weightBytes, "rows-weight", storage);
    r->colIndex = hostColumns ? gl::createBuffer(4 * entries, nullptr, storage, "columns-index") : zeroedBuffer(4 * entries, "columns-index");
    r->colWeight = hostColumns ? gl::createBuffer(weightBytes, nullptr, storage, "columns-weight") : zeroedBuffer(weightBytes, "columns-weight");
    // Pass 2: the same rays write their entries into their row and, on a GPU, into each element's
    // column. On a CPU rasterizer the host transposes the rows instead: the columns' scattered
    // writes and atomics made the fill pass 2.3× slower than the rows alone (1,450 against 630 ms
    // for 10 M entries, bench/solver_race (b)), and a counting sort on the host costs less.
    gl::Buffer cursor;  // where each column's next entry goes (the fill pass's atomics)
    if (!hostColumns) cursor = zeroedBuffer(4 * r->columns, "columns-cursor");
    gl::ShaderBuilder fill("project.comp");
    fill.define("VOLSTYLE_ROWS", VOLSTYLE_ROWS_FILL).define("VOLSTYLE_ROW_CHANNELS", channels).define("VOLSTYLE_ROW_MASK", masked);
    fill.define("VOLSTYLE_ROW_COLUMNS", hostColumns ? 0 : 1);
    useProgram(v, fill);
    bindStarts();
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowIndex, r->rowIndex.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowWeight, r->rowWeight.id());
    if (!hostColumns) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColCursor, cursor.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColIndex, r->colIndex.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColWeight, r->colWeight.id());
    }
    dispatchView(v);
    gl::barrierAfterComputeWrites();  // (it includes what the host's mapping of the rows needs)
    if (hostColumns) transposeOnHost(*r, rowStart);
    m_device.finish();
    r->buildMs = msSince(t0);
    return r;
}

void Projector::mergeRows(size_t budgetBytes) {
    size_t entries = 0;
    for (const View& v : m_views) entries += v.rows->entries;
    const int channels = m_views.front().rows->channels;
    const size_t bytes = sparseRowsBytes(m_pixelCount, elementCount(), entries, channels);
    if (entries == 0 || entries >= 0xffffffffu || m_stats.cacheBytes + bytes > budgetBytes ||
        (long long)(entries * 4 * size_t(channels)) > m_device.capabilities().maxStorageBlockBytes)
        return;
    auto m = std::make_unique<SparseRows>();
    m->rows = m_pixelCount, m->columns = elementCount(), m->entries = entries, m->channels = channels;
    // Rows: each view's, one after another; their starts shifted by the entries before them.
    std::vector<uint32_t> rowStart;
    rowStart.reserve(m_pixelCount + 1);
    std::vector<uint32_t> colCount(elementCount() + 1, 0), viewStarts;
    // On a CPU rasterizer whose views' columns the host made, the host merges them too (in place).
    m->hostMapped = m_columnsOnHost && std::all_of(m_views.begin(), m_views.end(), [](const View& v) { return v.rows->hostMapped; });
    const GLbitfield storage = m->hostMapped ? kHostMappedStorage : GL_DYNAMIC_STORAGE_BIT;
    m->rowIndex = gl::createBuffer(4 * entries, nullptr, storage, "merged-rows-index");
    m->rowWeight = gl::createBuffer(4 * entries * size_t(channels), nullptr, storage, "merged-rows-weight");
    size_t before = 0;
    for (const View& v : m_views) {
        const SparseRows& r = *v.rows;
        viewStarts.resize(r.rows + 1);
        glGetNamedBufferSubData(r.rowStart.id(), 0, GLsizeiptr(4 * (r.rows + 1)), viewStarts.data());
        for (size_t i = 0; i < r.rows; ++i) rowStart.push_back(uint32_t(before + viewStarts[i]));
        viewStarts.resize(r.columns + 1);
        glGetNamedBufferSubData(r.colStart.id(), 0, GLsizeiptr(4 * (r.columns + 1)), viewStarts.data());
        for (size_t e = 0; e < r.columns; ++e) colCount[e] += viewStarts[e + 1] - viewStarts[e];
        if (r.entries > 0) {
            glCopyNamedBufferSubData(r.rowIndex.id(), m->rowIndex.id(), 0, GLintptr(4 * before), GLsizeiptr(4 * r.entries));
            glCopyNamedBufferSubData(r.rowWeight.id(), m->rowWeight.id(), 0, GLintptr(4 * before * size_t(channels)),
                                     GLsizeiptr(4 * r.entries * size_t(channels)));
        }
        before += r.entries;
    }
    rowStart.push_back(uint32_t(entries));
    m->rowStart = gl::createBuffer(4 * rowStart.size(), rowStart.data(), m->hostMapped ? storage : 0, "merged-rows-start");
    exclusiveScan(colCount);  // counts -> starts (one extra total appended, unused)
    colCount.pop_back();
    m->colStart = gl::createBuffer(4 * colCount.size(), colCount.data(), m->hostMapped ? storage : 0, "merged-columns-start");
    m->colIndex = gl::createBuffer(4 * entries, nullptr, storage, "merged-columns-index");
    m->colWeight = gl::createBuffer(4 * entries * size_t(channels), nullptr, storage, "merged-columns-weight");
    if (m->hostMapped) {
        // bench/solver_race (b), two views of 10 M entries: 420 ms on llvmpipe by sparse_merge.comp.
        std::vector<const SparseRows*> views;
        std::vector<size_t> offsets;
        for (const View& v : m_views) views.push_back(v.rows.get()), offsets.push_back(v.offset);
        mergeColumnsOnHost(*m, colCount, views, offsets);
    } else {
        mergeColumnsOnDevice(*m);
    }
    m_stats.cacheBytes += bytes;
    m_merged = std::move(m);
    if (m_stats.cacheBytes > m_keepViewRowsBytes) dropViewRows();
}

void Projector::mergeColumnsOnDevice(SparseRows& m) {
    // Each element's entries of every view, in view order (sparse_merge.comp).
    const gl::Buffer cursor = zeroedBuffer(4 * elementCount(), "merged-columns-cursor");
    gl::ShaderBuilder builder("sparse_merge.comp");
    builder.define("VOLSTYLE_ROW_CHANNELS", m.channels);
    glUseProgram(m_device.program(builder).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColStart, m.colStart.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColCursor, cursor.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColIndex, m.colIndex.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingColWeight, m.colWeight.id());
    for (const View& v : m_views) {
        if (v.rows->entries == 0) continue;
        layout::SparseParams p;
        p.count = {int(elementCount()), int(v.offset), 0, -1};
        m_device.setParams(p);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowStart, v.rows->colStart.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowIndex, v.rows->colIndex.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingRowWeight, v.rows->colWeight.id());
        glDispatchCompute(GLuint((elementCount() + layout::kWorkgroup1D - 1) / layout::kWorkgroup1D), 1, 1);
        gl::barrierAfterComputeWrites();  // the next view appends after these
    }
}

void Projector::dropViewRows() {
    // The merged rows are every view's (a view is a range of them): the per-view rows hold the
    // same entries twice.
    for (View& v : m_views) {
        if (v.rows) m_stats.cacheBytes -= sparseRowsBytes(v.rows->rows, v.rows->columns, v.rows->entries, v.rows->channels);
        v.rows.reset();
    }
}

void Projector::adoptMergedRows(std::shared_ptr<const SparseRows> rows) {
    VOLSTYLE_CHECK(rows->rows, ==, m_pixelCount);
    VOLSTYLE_CHECK(rows->columns, ==, elementCount());
    if (m_merged) m_stats.cacheBytes -= sparseRowsBytes(m_merged->rows, m_merged->columns, m_merged->entries, m_merged->channels);
    m_stats.cacheBytes += sparseRowsBytes(rows->rows, rows->columns, rows->entries, rows->channels);
    m_merged = std::move(rows);
    dropViewRows();  // adopted before any view's own (Solver: the merged rows are looked up first)
    m_stats.cachedViews = m_views.size();
    m_stats.cachedEntries = m_merged->entries;
}

void Projector::adoptRows(size_t view, std::shared_ptr<const SparseRows> rows) {
    View& v = m_views.at(view);
    VOLSTYLE_CHECK(rows->rows, ==, size_t(v.camera.width) * v.camera.height);
    VOLSTYLE_CHECK(rows->columns, ==, elementCount());
    VOLSTYLE_CHECK(m_merged == nullptr, ==, true);  // merged rows are every view's: adopt them whole
    if (!v.rows) m_stats.cachedViews++;
    else {
        m_stats.cacheBytes -= sparseRowsBytes(v.rows->rows, v.rows->columns, v.rows->entries, v.rows->channels);
        m_stats.cachedEntries -= v.rows->entries;
    }
    m_stats.cacheBytes += sparseRowsBytes(rows->rows, rows->columns, rows->entries, rows->channels);
    m_stats.cachedEntries += rows->entries;
    v.rows = std::move(rows);
}

void Projector::cacheRows(size_t budgetBytes, int channels, const GpuVector* pixelMask) {
    if (pixelMask) VOLSTYLE_CHECK(pixelMask->size(), ==, m_pixelCount);
    const auto t0 = Clock::now();
    for (View& v : m_views) {
        if (v.rows || m_merged) continue;
        const size_t left = budgetBytes > m_stats.cacheBytes ? budgetBytes - m_stats.cacheBytes : 0;
        v.rows = buildRows(v, left, channels, pixelMask);
        if (!v.rows) {
            spdlog::info("solve: rows of W past the cache budget ({} MiB) from view {} on: matrix-free there",
                         budgetBytes >> 20, &v - m_views.data());
            break;
        }
        m_stats.cacheBytes += sparseRowsBytes(v.rows->rows, v.rows->columns, v.rows->entries, channels);
        m_stats.cachedEntries += v.rows->entries;
        m_stats.cachedViews++;
    }
    if (allCached() && m_views.size() > 1 && !m_merged && m_mergeViews) mergeRows(budgetBytes);
    m_device.finish();
    m_stats.cacheMs += msSince(t0);
}

void Projector::setSupports(std::shared_ptr<const Support> pixels, std::shared_ptr<const Support> elements) {
    m_pixelSupport = std::move(pixels);
    m_elementSupport = std::move(elements);
}

void Projector::timed(bool adjoint, const std::function<void()>& work) {
    const auto t0 = Clock::now();
    work();
    m_device.finish();
    (adjoint ? m_stats.adjointMs : m_stats.forwardMs) += msSince(t0);
    (adjoint ? m_stats.adjointCalls : m_stats.forwardCalls)++;
}

void Projector::gatherRows(const SparseRows& rows, Range view, size_t pixelOffset, const GpuVector& a, GpuVector& pixels,
                           const Support* only) {
    const bool whole = view.first == 0 && view.count == size_t(-1);
    if (m_productsOnHost && hostCanApply(rows, a, pixels)) hostForward(rows, view, a, pixels, pixelOffset, only);
    else if (whole) sparseForward(m_device, rows, a, pixels, pixelOffset, only);
    else sparseForwardRange(m_device, rows, view, a, pixels, only);  // pixelOffset is view.first
}

void Projector::gatherColumns(const SparseRows& rows, size_t pixelOffset, Range pixelsRead, const GpuVector& pixels, GpuVector& a,
                              const Support* only) {
    const bool whole = pixelsRead.first == 0 && pixelsRead.count == size_t(-1);
    if (m_productsOnHost && hostCanApply(rows, a, pixels)) hostAdjointAdd(rows, pixels, pixelOffset, a, only, pixelsRead);
    else if (whole) sparseAdjointAdd(m_device, rows, pixels, pixelOffset, a, only);
    else sparseAdjointAddRange(m_device, rows, pixelsRead, pixels, a, only);
}

void Projector::forward(const GpuVector& a, GpuVector& pixels) {
    timed(false, [&] {
        const Support* only = allCached() ? m_pixelSupport.get() : nullptr;
        if (m_merged) {
            gatherRows(*m_merged, {}, 0, a, pixels, only);
        } else {
            dispatch(false, a, pixels);
            for (const View& v : m_views)
                if (v.rows) gatherRows(*v.rows, {}, v.offset, a, pixels, only);
        }
        gl::barrierAfterComputeWrites();
    });
}

void Projector::adjoint(const GpuVector& pixels, GpuVector& a) {
    timed(true, [&] {
        a.fill(0.0f);
        if (m_merged) {
            gatherColumns(*m_merged, 0, {}, pixels, a, m_elementSupport.get());
            gl::barrierAfterComputeWrites();
            return;
        }
        dispatch(true, a, pixels);
        for (const View& v : m_views) {
            if (!v.rows) continue;
            gatherColumns(*v.rows, v.offset, {}, pixels, a, allCached() ? m_elementSupport.get() : nullptr);
            gl::barrierAfterComputeWrites();  // the next view adds to the same elements
        }
    });
}

void Projector::forwardByColumns(const GpuVector& c, GpuVector& pixels) {
    VOLSTYLE_CHECK(canForwardByColumns(), ==, true);
    timed(false, [&] {
        pixels.fill(0.0f);
        sparseForwardByColumns(m_device, m_merged ? *m_merged : *m_views.front().rows, c, pixels, 0, m_elementSupport.get(),
                               m_useFloatAtomics);
        gl::barrierAfterComputeWrites();
    });
}

void Projector::forwardView(size_t view, const GpuVector& a, GpuVector& pixels) {
    const View& v = m_views.at(view);
    timed(false, [&] {
        if (v.rows) gatherRows(*v.rows, {}, v.offset, a, pixels, allCached() ? m_pixelSupport.get() : nullptr);
        else if (m_merged) gatherRows(*m_merged, viewRange(view), viewRange(view).first, a, pixels, m_pixelSupport.get());
        else dispatch(false, a, pixels, &v);
        gl::barrierAfterComputeWrites();
    });
}

void Projector::adjointView(size_t view, const GpuVector& pixels, GpuVector& a) {
    const View& v = m_views.at(view);
    timed(true, [&] {
        a.fill(0.0f);
        if (v.rows) gatherColumns(*v.rows, v.offset, {}, pixels, a, allCached() ? m_elementSupport.get() : nullptr);
        else if (m_merged) gatherColumns(*m_merged, 0, viewRange(view), pixels, a, m_elementSupport.get());
        else dispatch(true, a, pixels, &v);
        gl::barrierAfterComputeWrites();
    });
}

void Projector::markThroughRows(bool columns, const Support& list, GpuVector& marks) const {
    VOLSTYLE_CHECK(allCached(), ==, true);
    if (m_merged) {
        sparseMark(m_device, *m_merged, columns, list, 0, marks);  // rows and columns over every view's pixels
        return;
    }
    for (const View& v : m_views) sparseMark(m_device, *v.rows, columns, list, v.offset, marks);
}

}  // namespace volstyle::core
