#include "core/solve/host_vector_ops.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/base/parallel.h"
#include "core/gl/mapped_buffer.h"
#include "core/shaders/layout.h"

namespace volstyle::core {
namespace {

constexpr size_t kChunk = 16384;
constexpr double kNone = 1e300;  // no bound (vector_ops.comp's kNone)

/// The operands' buffers mapped once each (x, y and z may be one vector: dot(r, r)).
class Mapped {
public:
    float* map(const GpuVector* v, bool write) {
        if (!v) return nullptr;
        for (auto& [id, m] : m_maps)
            if (id == v->id()) return m->as<float>();
        m_maps.emplace_back(v->id(), std::make_unique<gl::MappedBuffer>(v->buffer(), 16 * std::max<size_t>(v->size(), 1),
                                                                          GL_MAP_READ_BIT | (write ? GL_MAP_WRITE_BIT : 0)));
        return m_maps.back().second->as<float>();
    }

private:
    std::vector<std::pair<GLuint, std::unique_ptr<gl::MappedBuffer>>> m_maps;
};

/// [lower, upper] of element i's block (vector_ops.comp's boundsOf).
std::pair<float, float> boundsOf(const Bounds& b, size_t i) {
    const size_t block = i / std::max<size_t>(b.blockSize, 1);
    return block == 0 ? std::pair{b.lower[0], b.upper[0]} : std::pair{b.lower[1], b.upper[1]};
}

double stepToBound(float a, float p, std::pair<float, float> b) {
    if (p > 0.0f && b.second < 1e30f) return std::max(0.0, double(b.second - a) / double(p));
    if (p < 0.0f) return std::max(0.0, double(b.first - a) / double(p));
    return kNone;
}

double relativeChange(float x, float y, float z) { return z > 0.0f ? std::abs(double(x) - double(y)) / double(z) : 0.0; }

/// y = α · L x at element i (vector_ops.comp's LAPLACIAN, dense cells, x fastest).
void laplacianAt(const HostVectorOp& o, const float* x, float* y, const float* hull, size_t i) {
    const size_t cells = o.laplacianCells, block = i / cells, cell = i % cells;
    const Int3 n = o.dims;
    const int cx = int(cell % size_t(n.x)), cy = int((cell / size_t(n.x)) % size_t(n.y)), cz = int(cell / (size_t(n.x) * size_t(n.y)));
    float sum[3] = {0, 0, 0};
    if (hull[4 * i] > 0.0f) {
        const int offsets[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (const auto& d : offsets) {
            const int qx = cx + d[0], qy = cy + d[1], qz = cz + d[2];
            if (qx < 0 || qy < 0 || qz < 0 || qx >= n.x || qy >= n.y || qz >= n.z) continue;
            const size_t j = block * cells + (size_t(qz) * size_t(n.y) + size_t(qy)) * size_t(n.x) + size_t(qx);
            if (hull[4 * j] > 0.0f)
                for (int c = 0; c < 3; ++c) sum[c] += x[4 * j + size_t(c)] - x[4 * i + size_t(c)];
        }
    }
    for (int c = 0; c < 3; ++c) y[4 * i + size_t(c)] = o.alpha[c] * sum[c];
    y[4 * i + 3] = 0.0f;
}

/// The element-wise kernels at element i.
void elementAt(const HostVectorOp& o, const float* x, float* y, const float* z, size_t i) {
    float* yi = y + 4 * i;
    const float* xi = x ? x + 4 * i : nullptr;
    switch (o.op) {
        case VOLSTYLE_OP_AXPY:
            for (int c = 0; c < 3; ++c) yi[c] += o.alpha[c] * xi[c];
            break;
        case VOLSTYLE_OP_XPBY:
            for (int c = 0; c < 3; ++c) yi[c] = xi[c] + o.alpha[c] * yi[c];
            break;
        case VOLSTYLE_OP_MUL:
            for (int c = 0; c < 3; ++c) yi[c] *= xi[c];
            break;
        case VOLSTYLE_OP_LAPLACIAN: laplacianAt(o, x, y, z, i); break;
        case VOLSTYLE_OP_FREE: {
            const auto [lo, hi] = boundsOf(o.bounds, i);
            for (int c = 0; c < 3; ++c)
                if ((xi[c] <= lo && yi[c] < 0.0f) || (xi[c] >= hi && yi[c] > 0.0f)) yi[c] = 0.0f;
            break;
        }
        case VOLSTYLE_OP_CLAMP: {
            const auto [lo, hi] = boundsOf(o.bounds, i);
            for (int c = 0; c < 3; ++c) yi[c] = std::min(std::max(yi[c], lo), hi);  // GLSL's clamp
            break;
        }
        default: break;
    }
}

/// The reductions' value at element i, folded into acc (sum, min or max per channel).
void reduceAt(const HostVectorOp& o, const float* x, const float* y, const float* z, size_t i, double acc[3]) {
    const float *xi = x + 4 * i, *yi = y + 4 * i;
    switch (o.op) {
        case VOLSTYLE_OP_STEP: {
            const auto b = boundsOf(o.bounds, i);
            for (int c = 0; c < 3; ++c) acc[c] = std::min(acc[c], stepToBound(xi[c], yi[c], b));
            break;
        }
        case VOLSTYLE_OP_MAXCHANGE:
            for (int c = 0; c < 3; ++c) acc[c] = std::max(acc[c], relativeChange(xi[c], yi[c], z[4 * i + size_t(c)]));
            break;
        default:  // DOT, DOT_SEGMENTS
            for (int c = 0; c < 3; ++c) acc[c] += double(xi[c]) * double(yi[c]);
    }
}

/// The reduction over positions [first, first + count): per chunk, combined in chunk order.
std::vector<double> reduce(const HostVectorOp& o, const float* x, const float* y, const float* z, size_t first, size_t count) {
    const double start = o.op == VOLSTYLE_OP_STEP ? kNone : 0.0;
    auto combine = [&](double a, double b) {
        return o.op == VOLSTYLE_OP_STEP ? std::min(a, b) : o.op == VOLSTYLE_OP_MAXCHANGE ? std::max(a, b) : a + b;
    };
    std::vector<double> partial(3 * ((count + kChunk - 1) / kChunk), start);
    forEachChunk(count, kChunk, [&](size_t chunk, size_t lo, size_t hi) {
        double acc[3] = {start, start, start};
        for (size_t k = lo; k < hi; ++k) reduceAt(o, x, y, z, o.list ? o.list[first + k] : first + k, acc);
        std::copy_n(acc, 3, &partial[3 * chunk]);
    });
    std::vector<double> out = {start, start, start, o.op == VOLSTYLE_OP_STEP ? kNone : 0.0};
    for (size_t k = 0; k < partial.size(); k += 3)
        for (int c = 0; c < 3; ++c) out[size_t(c)] = combine(out[size_t(c)], partial[k + size_t(c)]);
    return out;
}

}  // namespace

bool hostCanRun(const HostVectorOp& op, bool sparseLaplacian) {
    if (sparseLaplacian) return false;
    for (const GpuVector* v : {op.x, op.y, op.z})
        if (v && !v->hostMapped()) return false;
    return true;
}

std::vector<double> runOnHost(const HostVectorOp& o) {
    const bool reduces = o.op == VOLSTYLE_OP_DOT || o.op == VOLSTYLE_OP_STEP || o.op == VOLSTYLE_OP_MAXCHANGE ||
                         o.op == VOLSTYLE_OP_DOT_SEGMENTS;
    gl::barrierAfterComputeWrites();  // a shader's writes to the vectors, before the host maps them
    Mapped maps;
    float* y = maps.map(o.y, !reduces);
    const float* x = maps.map(o.x, false);
    const float* z = maps.map(o.z, false);
    if (o.op == VOLSTYLE_OP_DOT_SEGMENTS) {
        std::vector<double> out;
        for (const auto& [first, count] : o.segments) {
            const std::vector<double> s = reduce(o, x, y, z, first, count);
            out.insert(out.end(), s.begin(), s.end());
        }
        return out;
    }
    if (reduces) return o.count > 0 ? reduce(o, x, y, z, o.first, o.count) : std::vector<double>{};
    forEachChunk(o.count, kChunk, [&](size_t, size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) elementAt(o, x, y, z, o.list ? o.list[o.first + k] : o.first + k);
    });
    return {};
}

}  // namespace volstyle::core
