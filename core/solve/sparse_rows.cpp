#include "core/solve/sparse_rows.h"

#include <algorithm>
#include <cstdint>

#include "core/base/errors.h"
#include "core/gl/shader_builder.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

size_t sparseRowsBytes(size_t rows, size_t columns, size_t entries, int channels) {
    const size_t perEntry = 4 * (1 + size_t(channels));  // index and weights, rows and columns alike
    return 4 * (rows + 1) + 4 * (columns + 1) + 2 * entries * perEntry;
}

int weightChannels(const Volume& volume, const Lighting& lighting, Unknown unknown) {
    if (unknown == Unknown::Extinction) return 1;  // segment lengths
    const std::vector<float>& sigma = volume.extinction();
    for (size_t i = 0; i + 2 < sigma.size(); i += 3)
        if (sigma[i] != sigma[i + 1] || sigma[i] != sigma[i + 2]) return 3;
    if (unknown == Unknown::Albedo || unknown == Unknown::EmissionAlbedo) {
        for (const auto& light : lighting.lights) {
            const Vec3d& e = light.irradiance;
            if (e.x != e.y || e.x != e.z) return 3;
        }
        if (lighting.environment.active())
            for (const Vec3d& e : lobeRadiance(lighting.environment))
                if (e.x != e.y || e.x != e.z) return 3;
    }
    return 1;
}

namespace {

/// Which rows of a cache a dispatch covers: all of a view's own, or one view's range of merged rows.
struct Part {
    size_t firstRow = 0;     ///< the cache's row of the view's first pixel
    size_t rows = SIZE_MAX;  ///< the view's pixels (SIZE_MAX: the cache's rows)
    size_t pixelsFrom = 0, pixelsTo = 0x7fffffff;  ///< Wᵀ: the input pixels read
};

/// W (rows) or Wᵀ (columns) over `only`'s part of this view, or with `mark` their entries' marks.
void apply(GpuDevice& device, const SparseRows& rows, bool adjoint, const GpuVector& in, GpuVector& out,
           size_t pixelOffset, const Support* only, bool mark = false, bool scatter = false, bool floatAtomics = false,
           Part part = {}) {
    size_t count = adjoint ? rows.columns : std::min(rows.rows, part.rows);
    const size_t outputOffset = adjoint ? 0 : pixelOffset;
    int listFirst = -1;
    if (only) {  // this view's part of the list: its pixels (W), every listed element (Wᵀ)
        const auto [lo, hi] = only->positions(outputOffset, count);
        listFirst = int(lo), count = hi - lo;
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSparseList, only->list.id());
    }
    if (count == 0) return;
    layout::SparseParams p;
    // Gathers read the input at count.y; a scatter (columns, unknowns in) writes pixels from there.
    p.count = {int(count), adjoint ? int(pixelOffset) : 0, int(outputOffset), listFirst};
    p.range = {adjoint ? 0 : int(part.firstRow), int(part.pixelsFrom), int(part.pixelsTo), 0};
    device.setParams(p);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSparseIn, in.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSparseOut, out.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSparseStart, (adjoint ? rows.colStart : rows.rowStart).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSparseIndex, (adjoint ? rows.colIndex : rows.rowIndex).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSparseWeight, (adjoint ? rows.colWeight : rows.rowWeight).id());
    gl::ShaderBuilder builder("sparse_project.comp");
    builder.define("VOLSTYLE_ADJOINT", adjoint ? 1 : 0).define("VOLSTYLE_ROW_CHANNELS", rows.channels).define("VOLSTYLE_MARK", mark ? 1 : 0);
    if (scatter) {
        builder.define("VOLSTYLE_SCATTER", 1);
        if (floatAtomics)
            builder.define("VOLSTYLE_HAS_FLOAT_ATOMICS", 1).extension("GL_NV_shader_atomic_float");
    }
    glUseProgram(device.program(builder).id());
    glDispatchCompute(GLuint((count + layout::kWorkgroup1D - 1) / layout::kWorkgroup1D), 1, 1);
}

}  // namespace

void sparseMark(GpuDevice& device, const SparseRows& rows, bool columns, const Support& list, size_t pixelOffset,
                GpuVector& marks) {
    apply(device, rows, columns, marks, marks, pixelOffset, &list, true);
}

void sparseForwardByColumns(GpuDevice& device, const SparseRows& rows, const GpuVector& c, GpuVector& pixels, size_t pixelOffset,
                            const Support* only, bool floatAtomics) {
    VOLSTYLE_CHECK(!floatAtomics || device.capabilities().hasFloatAtomics, ==, true);
    apply(device, rows, true, c, pixels, pixelOffset, only, false, true, floatAtomics);
}

void sparseForward(GpuDevice& device, const SparseRows& rows, const GpuVector& a, GpuVector& pixels, size_t pixelOffset,
                   const Support* only) {
    apply(device, rows, false, a, pixels, pixelOffset, only);
}

void sparseAdjointAdd(GpuDevice& device, const SparseRows& rows, const GpuVector& pixels, size_t pixelOffset, GpuVector& a,
                      const Support* only) {
    apply(device, rows, true, pixels, a, pixelOffset, only);
}

void sparseForwardRange(GpuDevice& device, const SparseRows& merged, Range view, const GpuVector& a, GpuVector& pixels,
                        const Support* only) {
    VOLSTYLE_CHECK(view.first + view.count, <=, merged.rows);
    apply(device, merged, false, a, pixels, view.first, only, false, false, false, Part{view.first, view.count});
}

void sparseAdjointAddRange(GpuDevice& device, const SparseRows& merged, Range view, const GpuVector& pixels, GpuVector& a,
                           const Support* only) {
    VOLSTYLE_CHECK(view.first + view.count, <=, merged.rows);
    apply(device, merged, true, pixels, a, 0, only, false, false, false, Part{0, SIZE_MAX, view.first, view.first + view.count});
}

}  // namespace volstyle::core
