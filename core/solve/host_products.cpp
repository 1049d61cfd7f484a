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

/// One product's buffers mapped in place: the rows (or columns) read, `in` read, `out` written.
struct MappedProduct {
    MappedProduct(const SparseRows& rows, bool columns, const GpuVector& in, const GpuVector& out)
        : channels(size_t(rows.channels)),
          startMap(columns ? rows.colStart : rows.rowStart, 4 * ((columns ? rows.columns : rows.rows) + 1), GL_MAP_READ_BIT),
          indexMap(columns ? rows.colIndex : rows.rowIndex, 4 * rows.entries, GL_MAP_READ_BIT),
          weightMap(columns ? rows.colWeight : rows.rowWeight, 4 * rows.entries * channels, GL_MAP_READ_BIT),
          inMap(in.buffer(), 16 * in.size(), GL_MAP_READ_BIT),
          outMap(out.buffer(), 16 * out.size(), GL_MAP_READ_BIT | GL_MAP_WRITE_BIT) {}

    /// Σ over entry list `i` (a row or column) of its inputs, from input x0 on (gather()).
    void sum(size_t i, const float* x0, uint32_t from, uint32_t to, float out[3]) const {
        const auto* start = startMap.as<const uint32_t>();
        const auto* index = indexMap.as<const uint32_t>();
        const auto* weight = weightMap.as<const float>();
        if (channels == 1) gather<1>(index, weight, x0, start[i], start[i + 1], from, to, out);
        else gather<3>(index, weight, x0, start[i], start[i + 1], from, to, out);
    }
    bool empty(size_t i) const { return startMap.as<const uint32_t>()[i] == startMap.as<const uint32_t>()[i + 1]; }
    const float* in() const { return inMap.as<const float>(); }
    float* out() const { return outMap.as<float>(); }

    const size_t channels;
    const gl::MappedBuffer startMap, indexMap, weightMap, inMap, outMap;
};

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
    const MappedProduct m(rows, false, a, pixels);
    inParallel(out.count, [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) {
            const size_t o = out[k];
            float* sum = m.out() + 4 * o;
            m.sum(o - pixelOffset + view.first, m.in(), 0, 0xffffffffu, sum);
            sum[3] = 0;
        }
    });
}

void hostAdjointAdd(const SparseRows& rows, const GpuVector& pixels, size_t pixelOffset, GpuVector& a, const Support* only,
                    Range pixelsRead) {
    const Outputs out = outputsOf(only, 0, rows.columns);
    if (out.count == 0 || rows.entries == 0) return;
    gl::barrierAfterComputeWrites();  // a shader's writes to the vectors, before the host maps them
    const uint32_t from = uint32_t(std::min<size_t>(pixelsRead.first, 0xffffffffu));
    const uint32_t to = uint32_t(std::min<size_t>(pixelsRead.count == size_t(-1) ? 0xffffffffu : pixelsRead.first + pixelsRead.count, 0xffffffffu));
    const MappedProduct m(rows, true, pixels, a);
    inParallel(out.count, [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) {
            const size_t e = out[k];
            if (m.empty(e)) continue;
            float sum[3];
            m.sum(e, m.in() + 4 * pixelOffset, from, to, sum);
            for (int c = 0; c < 3; ++c) m.out()[4 * e + size_t(c)] += sum[c];
        }
    });
}

}  // namespace volstyle::core
