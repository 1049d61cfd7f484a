#include "core/solve/gpu_vector.h"

#include <algorithm>

#include "core/base/errors.h"
#include "core/solve/host_vector_ops.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

GpuVector::GpuVector(size_t elements, const std::string& label, bool hostMapped)
    : m_buffer(gl::createBuffer(std::max<size_t>(elements, 1) * 16, nullptr,
                                GL_DYNAMIC_STORAGE_BIT | (hostMapped ? GL_MAP_READ_BIT | GL_MAP_WRITE_BIT : 0), label)),
      m_elements(elements),
      m_hostMapped(hostMapped) {
    fill(0.0f);
}

void GpuVector::upload(const std::vector<float>& rgba) {
    VOLSTYLE_CHECK(rgba.size(), ==, m_elements * 4);
    gl::writeBuffer(m_buffer, 0, rgba.size() * sizeof(float), rgba.data());
}

std::vector<float> GpuVector::download() const {
    std::vector<float> out(m_elements * 4);
    gl::barrierAfterComputeWrites();
    glGetNamedBufferSubData(m_buffer.id(), 0, GLsizeiptr(out.size() * sizeof(float)), out.data());
    return out;
}

void GpuVector::fill(float value) {
    glClearNamedBufferData(m_buffer.id(), GL_R32F, GL_RED, GL_FLOAT, &value);
}

Support::Support(std::vector<uint32_t> elements)
    : host(std::move(elements)),
      list(gl::createBuffer(std::max<size_t>(host.size(), 1) * 4, host.empty() ? nullptr : host.data(), 0, "support")) {}

std::pair<size_t, size_t> Support::positions(size_t first, size_t count) const {
    const auto lo = std::lower_bound(host.begin(), host.end(), uint64_t(first),
                                     [](uint32_t e, uint64_t v) { return uint64_t(e) < v; });
    const uint64_t end = count == size_t(-1) ? ~uint64_t(0) : uint64_t(first) + count;
    const auto hi = std::lower_bound(lo, host.end(), end, [](uint32_t e, uint64_t v) { return uint64_t(e) < v; });
    return {size_t(lo - host.begin()), size_t(hi - host.begin())};
}

SparseCells::SparseCells(const BrickLayout& bricks)
    : slotOfBrick(gl::createBuffer(bricks.slotTable().size() * 4, bricks.slotTable().data(), 0, "slot-of-brick")),
      offset(bricks.offset()),
      cells(bricks.storedVoxels()) {
    std::vector<int32_t> b(bricks.slots() * 4, -1);
    for (size_t s = 1; s < bricks.slots(); ++s) {
        const Int3 brick = bricks.brickOfSlot(s);
        b[4 * s] = brick.x, b[4 * s + 1] = brick.y, b[4 * s + 2] = brick.z;
    }
    brickOfSlot = gl::createBuffer(b.size() * 4, b.data(), 0, "brick-of-slot");
}

struct VectorOps::Dispatch {
    const GpuVector* x = nullptr;
    const GpuVector* y = nullptr;
    const GpuVector* z = nullptr;
    Vec3d alpha;
    Bounds bounds;
    Range range;
    Int3 dims;
    const SparseCells* sparse = nullptr;
    const std::vector<Range>* segments = nullptr;  ///< kDotSegments: one workgroup per range
};

VectorOps::VectorOps(GpuDevice& device) : m_device(device), m_onHost(solverKernelsOnHost(device)) {}

std::vector<double> VectorOps::run(Op op, const Dispatch& d) {
    const size_t size = d.y ? d.y->size() : d.x->size();
    const Support* support = d.y && d.y->support() ? d.y->support() : d.x ? d.x->support() : nullptr;
    // A range as positions in the support's list (or the elements themselves).
    auto positions = [&](const Range& r) {
        size_t first = std::min(r.first, size), count = std::min(r.count, size - first);
        if (support) {
            const auto [lo, hi] = support->positions(first, count);
            first = lo, count = hi - lo;
        }
        return std::pair{first, count};
    };
    auto [first, count] = positions(d.range);
    if (m_onHost) {
        HostVectorOp h;
        h.op = op, h.x = d.x, h.y = d.y, h.z = d.z, h.bounds = d.bounds, h.first = first, h.count = count;
        for (int c = 0; c < 3; ++c) h.alpha[c] = float(d.alpha[c]);
        h.list = support ? support->host.data() : nullptr;
        h.dims = d.dims, h.laplacianCells = size_t(d.dims.volume());
        if (d.segments)
            for (const Range& r : *d.segments) h.segments.push_back(positions(r));
        if (hostCanRun(h, d.sparse != nullptr)) return runOnHost(h);
    }
    if (d.segments) {
        std::vector<uint32_t> segments;
        for (const Range& r : *d.segments) {
            const auto [f, c] = positions(r);
            segments.push_back(uint32_t(f)), segments.push_back(uint32_t(c));
        }
        if (d.segments->size() > m_segmentCapacity) {
            m_segments = gl::createBuffer(d.segments->size() * 8, nullptr, GL_DYNAMIC_STORAGE_BIT, "vector-segments");
            m_segmentCapacity = d.segments->size();
        }
        gl::writeBuffer(m_segments, 0, segments.size() * 4, segments.data());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSegments, m_segments.id());
        first = 0, count = d.segments->size();  // the workgroups; the elements come from the segments
    }
    layout::VectorParams p;
    p.alpha = {float(d.alpha.x), float(d.alpha.y), float(d.alpha.z), 0};
    p.bounds = {d.bounds.lower[0], d.bounds.upper[0], d.bounds.lower[1], d.bounds.upper[1]};
    p.count = {int(count), int(first), int(std::max<size_t>(d.bounds.blockSize, 1)), 0};
    if (d.segments) p.count.x = 0;  // no element per invocation: each workgroup walks its segment
    if (op == kLaplacian) p.count.z = int(d.sparse ? d.sparse->cells : size_t(d.dims.volume()));
    p.dims = {d.dims.x, d.dims.y, d.dims.z, 0};
    if (d.sparse) p.sparseOffset = {d.sparse->offset.x, d.sparse->offset.y, d.sparse->offset.z, 1};
    m_device.setParams(p);

    const bool reduces = op == kDot || op == kStep || op == kMaxChange || op == kDotSegments;
    // Reductions loop over elements within fewer workgroups: fewer barriers and partials.
    constexpr size_t kReduceGroups = 64;
    size_t groups = std::max<size_t>(1, (count + layout::kWorkgroup1D - 1) / layout::kWorkgroup1D);
    if (reduces) groups = std::min(groups, kReduceGroups);
    if (op == kDotSegments) groups = count;
    if (reduces && groups > m_partialCapacity) {
        m_partials = gl::createBuffer(groups * 32, nullptr, GL_DYNAMIC_STORAGE_BIT, "vector-partials");
        m_partialCapacity = groups;
    }
    // Unused bindings still need a buffer behind them; point them at y or x.
    const GpuVector* any = d.y ? d.y : d.x;
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingVectorX, (d.x ? d.x : any)->id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingVectorY, (d.y ? d.y : any)->id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingVectorZ, (d.z ? d.z : any)->id());
    if (m_partials) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingPartials, m_partials.id());
    if (support) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingIndexList, support->list.id());
    gl::ShaderBuilder builder("vector_ops.comp");
    builder.define("VOLSTYLE_OP", op).define("VOLSTYLE_INDEXED", support ? 1 : 0);
    if (d.sparse) {
        builder.define("VOLSTYLE_SPARSE", 1);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingSlotOfBrick, d.sparse->slotOfBrick.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingBrickOfSlot, d.sparse->brickOfSlot.id());
    }
    glUseProgram(m_device.program(builder).id());
    if (count > 0) glDispatchCompute(GLuint(groups), 1, 1);
    gl::barrierAfterComputeWrites();
    if (!reduces || count == 0) return {};  // an empty reduction: its identity (as the host's kernels give)
    std::vector<double> partials(groups * 4);
    glGetNamedBufferSubData(m_partials.id(), 0, GLsizeiptr(groups * 32), partials.data());
    return partials;
}

void VectorOps::axpy(const Vec3d& alpha, const GpuVector& x, GpuVector& y, Range range) {
    Dispatch d;
    d.x = &x, d.y = &y, d.alpha = alpha, d.range = range;
    run(kAxpy, d);
}

void VectorOps::xpby(const GpuVector& x, const Vec3d& beta, GpuVector& y) {
    Dispatch d;
    d.x = &x, d.y = &y, d.alpha = beta;
    run(kXpby, d);
}

void VectorOps::multiply(const GpuVector& x, GpuVector& y, Range range) {
    Dispatch d;
    d.x = &x, d.y = &y;
    d.range = range;
    run(kMul, d);
}

std::vector<Vec3d> VectorOps::dots(const GpuVector& x, const GpuVector& y, const std::vector<Range>& ranges) {
    if (ranges.empty()) return {};
    Dispatch d;
    d.x = &x, d.y = &y, d.segments = &ranges;
    const std::vector<double> partials = run(kDotSegments, d);
    std::vector<Vec3d> out;
    for (size_t g = 0; g < ranges.size(); ++g) out.emplace_back(partials[4 * g], partials[4 * g + 1], partials[4 * g + 2]);
    return out;
}

Vec3d VectorOps::dot(const GpuVector& x, const GpuVector& y, Range range) {
    Dispatch d;
    d.x = &x, d.y = &y, d.range = range;
    auto partials = run(kDot, d);
    Vec3d sum(0.0);
    for (size_t g = 0; g < partials.size(); g += 4) sum += Vec3d(partials[g], partials[g + 1], partials[g + 2]);
    return sum;
}

void VectorOps::laplacian(double scale, const GpuVector& x, const GpuVector& hull, Int3 dims, GpuVector& out, Range range,
                          const SparseCells* sparse) {
    Dispatch d;
    d.x = &x, d.y = &out, d.z = &hull, d.alpha = Vec3d(scale), d.dims = dims, d.range = range, d.sparse = sparse;
    run(kLaplacian, d);
}

void VectorOps::freeSet(const GpuVector& a, GpuVector& s, const Bounds& bounds) {
    Dispatch d;
    d.x = &a, d.y = &s, d.bounds = bounds;
    run(kFree, d);
}

Vec3d VectorOps::maxStep(const GpuVector& a, const GpuVector& p, const Bounds& bounds) {
    Dispatch d;
    d.x = &a, d.y = &p, d.bounds = bounds;
    auto partials = run(kStep, d);
    Vec3d m(1e300);
    for (size_t g = 0; g < partials.size(); g += 4)
        for (int c = 0; c < 3; ++c) m[c] = std::min(m[c], partials[g + size_t(c)]);
    return m;
}

Vec3d VectorOps::maxChange(const GpuVector& x, const GpuVector& y, const GpuVector& scale) {
    Dispatch d;
    d.x = &x, d.y = &y, d.z = &scale;
    auto partials = run(kMaxChange, d);
    Vec3d m(0.0);
    for (size_t g = 0; g < partials.size(); g += 4)
        for (int c = 0; c < 3; ++c) m[c] = std::max(m[c], partials[g + size_t(c)]);
    return m;
}

void VectorOps::clamp(GpuVector& a, const Bounds& bounds) {
    Dispatch d;
    d.y = &a, d.bounds = bounds;
    run(kClamp, d);
}

void VectorOps::copy(const GpuVector& from, GpuVector& to) {
    VOLSTYLE_CHECK(from.size(), ==, to.size());
    glCopyNamedBufferSubData(from.id(), to.id(), 0, 0, GLsizeiptr(from.size() * 16));
}

}  // namespace volstyle::core
