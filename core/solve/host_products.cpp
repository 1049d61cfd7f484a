#include "core/solve/host_products.h"

#include <algorithm>

#include "core/base/errors.h"
#include "core/base/parallel.h"
#include "core/gl/mapped_buffer.h"

namespace volstyle::core {
namespace {

/// Runs work(lo, hi) over [0, count) on every core (rows and columns differ widely in length).
template <typename Work>
void inParallel(size_t count, const Work& work) {
    forEachChunk(count, 2048, [&](size_t, size_t lo, size_t hi) { work(lo, hi); });
}

/// Σ_k w_k x[index_k] over entries [first, last) (x: vec4 per element, rgb used), in entry order
/// as sparse_project.comp sums; with `from`/`to`, only entries whose index lies in [from, to).
template <int Channels>
void gather(const uint32_t* index, const float* weight, const float* x, size_t first, size_t last, uint32_t from, uint32_t to,
            float sum[3]) {
    float s0 = 0, s1 = 0, s2 = 0;
    for (size_t k = first; k < last; ++k) {
        const uint32_t i = index[k];
        if (i < from || i >= to) continue;
        const float* v = x + 4 * size_t(i);
        const float w0 = weight[Channels * k], w1 = Channels == 1 ? w0 : weight[Channels * k + 1],
                    w2 = Channels == 1 ? w0 : weight[Channels * k + 2];
        s0 += w0 * v[0], s1 += w1 * v[1], s2 += w2 * v[2];
    }
    sum[0] = s0, sum[1] = s1, sum[2] = s2;
}

/// The outputs [first, first + count) a product writes, or `only`'s of them: their positions.
struct Outputs {
    const uint32_t* list = nullptr;
    size_t first = 0, count = 0;
    size_t operator[](size_t k) const { return list ? list[first + k] : first + k; }
};

Outputs outputsOf(const Support* only, size_t first, size_t count) {
    if (!only) return {nullptr, first, count};
    const auto [lo, hi] = only->positions(first, count);
    return {only->host.data(), lo, hi - lo};
}

}  // namespace

bool hostCanApply(const SparseRows& rows, const GpuVector& a, const GpuVector& pixels) {
    return rows.hostMapped && a.hostMapped() && pixels.hostMapped();
}

void hostForward(const SparseRows& rows, Range view, const GpuVector& a, GpuVector& pixels, size_t pixelOffset, const Support* only) {
    VOLSTYLE_CHECK(view.first, <=, rows.rows);
    const size_t count = std::min(rows.rows - view.first, view.count);
    const Outputs out = outputsOf(only, pixelOffset, count);
    if (out.count == 0) return;
    gl::barrierAfterComputeWrites();  // a shader's writes to the vectors, before the host maps them
    const size_t ch = size_t(rows.channels);
    const gl::MappedBuffer startMap(rows.rowStart, 4 * (rows.rows + 1), GL_MAP_READ_BIT);
    const gl::MappedBuffer indexMap(rows.rowIndex, 4 * rows.entries, GL_MAP_READ_BIT);
    const gl::MappedBuffer weightMap(rows.rowWeight, 4 * rows.entries * ch, GL_MAP_READ_BIT);
    const gl::MappedBuffer inMap(a.buffer(), 16 * a.size(), GL_MAP_READ_BIT);
    const gl::MappedBuffer outMap(pixels.buffer(), 16 * pixels.size(), GL_MAP_READ_BIT | GL_MAP_WRITE_BIT);
    const auto* start = startMap.as<const uint32_t>();
    const auto* index = indexMap.as<const uint32_t>();
    const auto* weight = weightMap.as<const float>();
    const auto* x = inMap.as<const float>();
    auto* y = outMap.as<float>();
    inParallel(out.count, [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) {
            const size_t o = out[k], row = o - pixelOffset + view.first;
            float* sum = y + 4 * o;
            if (ch == 1) gather<1>(index, weight, x, start[row], start[row + 1], 0, 0xffffffffu, sum);
            else gather<3>(index, weight, x, start[row], start[row + 1], 0, 0xffffffffu, sum);
            sum[3] = 0;
        }
    });
}

void hostAdjointAdd(const SparseRows& rows, const GpuVector& pixels, size_t pixelOffset, GpuVector& a, const Support* only,
                    Range pixelsRead) {
    const Outputs out = outputsOf(only, 0, rows.columns);
    if (out.count == 0 || rows.entries == 0) return;
    gl::barrierAfterComputeWrites();  // a shader's writes to the vectors, before the host maps them
    const size_t ch = size_t(rows.channels);
    const uint32_t from = uint32_t(std::min<size_t>(pixelsRead.first, 0xffffffffu));
    const uint32_t to = uint32_t(std::min<size_t>(pixelsRead.count == size_t(-1) ? 0xffffffffu : pixelsRead.first + pixelsRead.count, 0xffffffffu));
    const gl::MappedBuffer startMap(rows.colStart, 4 * (rows.columns + 1), GL_MAP_READ_BIT);
    const gl::MappedBuffer indexMap(rows.colIndex, 4 * rows.entries, GL_MAP_READ_BIT);
    const gl::MappedBuffer weightMap(rows.colWeight, 4 * rows.entries * ch, GL_MAP_READ_BIT);
    const gl::MappedBuffer inMap(pixels.buffer(), 16 * pixels.size(), GL_MAP_READ_BIT);
    const gl::MappedBuffer outMap(a.buffer(), 16 * a.size(), GL_MAP_READ_BIT | GL_MAP_WRITE_BIT);
    const auto* start = startMap.as<const uint32_t>();
    const auto* index = indexMap.as<const uint32_t>();
    const auto* weight = weightMap.as<const float>();
    const float* x = inMap.as<const float>() + 4 * pixelOffset;
    auto* y = outMap.as<float>();
    inParallel(out.count, [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) {
            const size_t e = out[k];
            if (start[e] == start[e + 1]) continue;
            float sum[3];
            if (ch == 1) gather<1>(index, weight, x, start[e], start[e + 1], from, to, sum);
            else gather<3>(index, weight, x, start[e], start[e + 1], from, to, sum);
            for (int c = 0; c < 3; ++c) y[4 * e + size_t(c)] += sum[c];
        }
    });
}

}  // namespace volstyle::core
