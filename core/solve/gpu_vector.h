#pragma once
/// \file gpu_vector.h
/// GPU-resident solver vectors (arrays of vec4, rgb = three independent channels) and the
/// operations CGLS needs on them, each one dispatch of vector_ops.comp. Reductions accumulate in
/// float64 on the GPU and finish on the host. GL thread only.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/gpu/gpu_device.h"
#include "core/math/vec.h"
#include "core/shaders/layout.h"
#include "core/volume/brick_layout.h"

namespace volstyle::core {

/// The elements a vector's operations touch, ascending: the solver's hull voxels or constrained
/// pixels (13% and 28% of the race's (a)). The others are never read by an operation on the
/// vector and keep what they hold. Shared by every vector of one space.
struct Support {
    explicit Support(std::vector<uint32_t> elements);
    std::vector<uint32_t> host;
    gl::Buffer list;
    /// Positions in the list of the elements in [first, first + count).
    std::pair<size_t, size_t> positions(size_t first, size_t count) const;
};

/// Whether the solver's vectors are host-mapped and its products and vector kernels run on the
/// host by default (host_products.h, host_vector_ops.h): on a CPU rasterizer, whose buffers are
/// the process's own memory.
inline bool solverKernelsOnHost(const GpuDevice& device) { return device.capabilities().isSoftware; }

class GpuVector {
public:
    GpuVector() = default;
    /// `hostMapped`: storage the host can map in place (host_products.h; on a CPU rasterizer).
    GpuVector(size_t elements, const std::string& label, bool hostMapped = false);
    size_t size() const { return m_elements; }
    GLuint id() const { return m_buffer.id(); }
    const gl::Buffer& buffer() const { return m_buffer; }
    bool hostMapped() const { return m_hostMapped; }
    void upload(const std::vector<float>& rgba);  ///< 4 floats per element
    std::vector<float> download() const;
    void fill(float value);
    /// Restricts the vector operations on this vector (as output, or as input of a reduction)
    /// to these elements; null: all. Copies and fills still cover every element.
    void setSupport(std::shared_ptr<const Support> support) { m_support = std::move(support); }
    const Support* support() const { return m_support.get(); }

private:
    gl::Buffer m_buffer;
    size_t m_elements = 0;
    bool m_hostMapped = false;
    std::shared_ptr<const Support> m_support;
};

/// Box constraints per block of unknowns (block = element / blockSize; at most two blocks).
struct Bounds {
    float lower[2] = {-3e38f, -3e38f};
    float upper[2] = {3e38f, 3e38f};
    size_t blockSize = 0;
};

/// A sub-range of elements.
struct Range {
    size_t first = 0;
    size_t count = size_t(-1);  ///< -1: to the end
};

/// A sparse volume's cells for the Laplacian (brick_layout.h): its brick-to-slot table and each
/// slot's brick, on the GPU.
struct SparseCells {
    explicit SparseCells(const BrickLayout& bricks);
    gl::Buffer slotOfBrick, brickOfSlot;
    Int3 offset;
    size_t cells = 0;  ///< stored voxels (slots × 8³)
};

class VectorOps {
public:
    explicit VectorOps(GpuDevice& device);
    /// Whether operations whose vectors are all hostMapped run on the host (host_vector_ops.h;
    /// the default on a CPU rasterizer) or in vector_ops.comp.
    void setOnHost(bool onHost) { m_onHost = onHost; }
    void axpy(const Vec3d& alpha, const GpuVector& x, GpuVector& y, Range range = {});  ///< y += αx
    void xpby(const GpuVector& x, const Vec3d& beta, GpuVector& y);                     ///< y = x + βy
    void multiply(const GpuVector& x, GpuVector& y, Range range = {});                 ///< y ⊙= x
    Vec3d dot(const GpuVector& x, const GpuVector& y, Range range = {});
    /// dot(x, y, range) for each range, in one dispatch and one read-back (each view's pixels:
    /// the per-view RMS of every iteration).
    std::vector<Vec3d> dots(const GpuVector& x, const GpuVector& y, const std::vector<Range>& ranges);
    /// out = scale · L x over the cells of `hull` (rgb > 0), per block of `dims` cells (or of a
    /// sparse volume's stored voxels, neighbours found through `sparse`).
    void laplacian(double scale, const GpuVector& x, const GpuVector& hull, Int3 dims, GpuVector& out, Range range = {},
                   const SparseCells* sparse = nullptr);
    /// Zeroes s where a is at a bound and s points past it.
    void freeSet(const GpuVector& a, GpuVector& s, const Bounds& bounds);
    /// Per channel, the largest t ≥ 0 with a + t·p inside the bounds (1e300 if unbounded).
    Vec3d maxStep(const GpuVector& a, const GpuVector& p, const Bounds& bounds);
    void clamp(GpuVector& a, const Bounds& bounds);
    /// Per channel, max over i with scale[i] > 0 of |x[i] − y[i]| / scale[i].
    Vec3d maxChange(const GpuVector& x, const GpuVector& y, const GpuVector& scale);
    void copy(const GpuVector& from, GpuVector& to);

private:
    /// The kernels of vector_ops.comp; the values are its VOLSTYLE_OP_* constants (layout.h).
    enum Op {
        kAxpy = VOLSTYLE_OP_AXPY,
        kXpby = VOLSTYLE_OP_XPBY,
        kMul = VOLSTYLE_OP_MUL,
        kDot = VOLSTYLE_OP_DOT,
        kLaplacian = VOLSTYLE_OP_LAPLACIAN,
        kFree = VOLSTYLE_OP_FREE,
        kStep = VOLSTYLE_OP_STEP,
        kClamp = VOLSTYLE_OP_CLAMP,
        kMaxChange = VOLSTYLE_OP_MAXCHANGE,
        kDotSegments = VOLSTYLE_OP_DOT_SEGMENTS,
    };
    struct Dispatch;
    std::vector<double> run(Op op, const Dispatch& d);

    GpuDevice& m_device;
    bool m_onHost = false;
    gl::Buffer m_partials;
    size_t m_partialCapacity = 0;
    gl::Buffer m_segments;  // kDotSegments: (first position, count) per range
    size_t m_segmentCapacity = 0;
};

}  // namespace volstyle::core
