// The solver's vector operations, all on the GPU (TVCG Sec. 5.1: "all necessary steps of the
// conjugate gradient method are carried out on the GPU"). Vectors are arrays of vec4 whose rgb
// are three independent channels; scalars are per channel (vec4 alpha). VOLSTYLE_OP picks one:
//   VOLSTYLE_OP_AXPY      y[i] += alpha * x[i]
//   VOLSTYLE_OP_XPBY      y[i]  = x[i] + alpha * y[i]
//   VOLSTYLE_OP_MUL       y[i] *= x[i]
//   VOLSTYLE_OP_DOT       partial[workgroup] = Σ x[i]·y[i] per channel, accumulated in double: float sums
//                drift on large grids and would fake divergence (reductions run grid-stride loops
//                over at most kReduceGroups workgroups)
//   VOLSTYLE_OP_LAPLACIAN y = alpha · L x, the 7-point Laplacian over the cells where z (the hull) is set:
//                (L x)_i = Σ_{j ∈ N6(i), j in hull} (x_j − x_i) (symmetric, so Lᵀ = L)
//   VOLSTYLE_OP_FREE      y[i] = 0 where x (the unknowns) sits at a bound and y would push past it
//   VOLSTYLE_OP_STEP      partial[workgroup] = min over i of the step t ≥ 0 at which x + t·y meets a bound
//   VOLSTYLE_OP_CLAMP     y = clamp(y, lower, upper)
//   VOLSTYLE_OP_MAXCHANGE partial[workgroup] = max over i with z[i] > 0 of |x[i] − y[i]| / z[i]: how much a
//                pixel changed between two weighted residuals (z = the weights' square roots)
//   VOLSTYLE_OP_DOT_SEGMENTS partial[g] = Σ x[i]·y[i] over segment g (segments[g]: first position, count):
//                one workgroup per segment, so the dots of every view's pixels are one dispatch
// Elements [first, first + count) are processed (VOLSTYLE_INDEXED: list[first .. first + count),
// the solver's hull voxels or constrained pixels; the others keep their values); element i belongs to block i / blockSize, whose
// bounds are bounds.xy (block 0) or bounds.zw (block 1).
#include "layout.h"

layout(local_size_x = kWorkgroup1D) in;

layout(std140, binding = kBindingParams) uniform b_VectorParams {
    VectorParams v;
};
layout(std430, binding = kBindingVectorX) readonly buffer b_X {
    vec4 x[];
};
layout(std430, binding = kBindingVectorY) buffer b_Y {
    vec4 y[];
};
layout(std430, binding = kBindingVectorZ) readonly buffer b_Z {
    vec4 z[];
};
layout(std430, binding = kBindingPartials) writeonly buffer b_Partials {
    dvec4 partial[];
};
#ifndef VOLSTYLE_INDEXED
#define VOLSTYLE_INDEXED 0
#endif
#ifndef VOLSTYLE_SPARSE
#define VOLSTYLE_SPARSE 0
#endif

// The Laplacian's cells: the voxels of a dense grid (x fastest), or a sparse volume's stored
// voxels (slot · 8³ + place in the brick; core/volume/brick_layout.h).
#if VOLSTYLE_SPARSE
layout(std430, binding = kBindingSlotOfBrick) readonly buffer b_SlotOfBrick {
    uint slotOfBrick[];
};
layout(std430, binding = kBindingBrickOfSlot) readonly buffer b_BrickOfSlot {
    ivec4 brickOfSlot[];
};
const int kCellsPerBrick = kBrickSize * kBrickSize * kBrickSize;
ivec3 voxelOfCell(int cell) {
    int l = cell % kCellsPerBrick;
    return brickOfSlot[cell / kCellsPerBrick].xyz * kBrickSize - v.sparseOffset.xyz +
           ivec3(l % kBrickSize, (l / kBrickSize) % kBrickSize, l / (kBrickSize * kBrickSize));
}
int cellOfVoxel(ivec3 q) {
    ivec3 s = q + v.sparseOffset.xyz, b = s / kBrickSize, l = s % kBrickSize;
    ivec3 bricks = (v.dims.xyz + v.sparseOffset.xyz + kBrickSize - 1) / kBrickSize;
    int slot = int(slotOfBrick[(b.z * bricks.y + b.y) * bricks.x + b.x]);
    return slot * kCellsPerBrick + (l.z * kBrickSize + l.y) * kBrickSize + l.x;
}
#else
ivec3 voxelOfCell(int cell) {
    ivec3 n = v.dims.xyz;
    return ivec3(cell % n.x, (cell / n.x) % n.y, cell / (n.x * n.y));
}
int cellOfVoxel(ivec3 q) { return (q.z * v.dims.y + q.y) * v.dims.x + q.x; }
#endif
#if VOLSTYLE_INDEXED
layout(std430, binding = kBindingIndexList) readonly buffer b_List {
    uint list[];
};
uint elementAt(uint k) { return list[uint(v.count.y) + k]; }
#else
uint elementAt(uint k) { return uint(v.count.y) + k; }
#endif

// VOLSTYLE_OP_* come from layout.h (core::VectorOps::Op takes the same values).

#if VOLSTYLE_OP == VOLSTYLE_OP_DOT || VOLSTYLE_OP == VOLSTYLE_OP_STEP || VOLSTYLE_OP == VOLSTYLE_OP_MAXCHANGE || \
    VOLSTYLE_OP == VOLSTYLE_OP_DOT_SEGMENTS
shared dvec4 s_reduce[kWorkgroup1D];
#endif
#if VOLSTYLE_OP == VOLSTYLE_OP_DOT_SEGMENTS
layout(std430, binding = kBindingSegments) readonly buffer b_Segments {
    uvec2 segments[];
};
#endif

vec2 boundsOf(uint i) { return (int(i) / v.count.z) == 0 ? v.bounds.xy : v.bounds.zw; }

// Per-component helpers for STEP and MAXCHANGE: a dvec4 written at a loop index (t[c] = …) makes
// NVIDIA's linker fail ("can't find __setVectorIndex"), so the components are named instead.
const double kNone = 1e300lf;  // no bound; lf: as a float literal it overflows (NVIDIA refuses it)
// The longest step along p from a that stays inside [b.x, b.y] (an upper bound ≥ 1e30 is none).
double stepToBound(float a, float p, vec2 b) {
    if (p > 0.0 && b.y < 1e30) return max(0.0lf, double(b.y - a) / double(p));
    if (p < 0.0) return max(0.0lf, double(b.x - a) / double(p));
    return kNone;
}
// |x − y| / z where z > 0 (the relative change), else 0.
double relativeChange(float x, float y, float z) { return z > 0.0 ? abs(double(x) - double(y)) / double(z) : 0.0lf; }

void main() {
    uint local = gl_LocalInvocationID.x;
    uint k = gl_GlobalInvocationID.x;
    bool inside = k < uint(v.count.x);
    uint i = inside ? elementAt(k) : 0u;

#if VOLSTYLE_OP == VOLSTYLE_OP_AXPY
    if (inside) y[i].rgb += v.alpha.rgb * x[i].rgb;
#elif VOLSTYLE_OP == VOLSTYLE_OP_XPBY
    if (inside) y[i].rgb = x[i].rgb + v.alpha.rgb * y[i].rgb;
#elif VOLSTYLE_OP == VOLSTYLE_OP_MUL
    if (inside) y[i].rgb *= x[i].rgb;
#elif VOLSTYLE_OP == VOLSTYLE_OP_DOT
    // Grid-stride: few workgroups, so few barriers (costly on llvmpipe) and few partials to read.
    dvec4 acc = dvec4(0.0);
    for (uint e = k; e < uint(v.count.x); e += gl_NumWorkGroups.x * kWorkgroup1D) {
        uint j = elementAt(e);
        acc.rgb += dvec3(x[j].rgb) * dvec3(y[j].rgb);
    }
    s_reduce[local] = acc;
    barrier();
    for (uint stride = kWorkgroup1D / 2; stride > 0; stride >>= 1) {
        if (local < stride) s_reduce[local] += s_reduce[local + stride];
        barrier();
    }
    if (local == 0) partial[gl_WorkGroupID.x] = s_reduce[0];
#elif VOLSTYLE_OP == VOLSTYLE_OP_DOT_SEGMENTS
    uvec2 segment = segments[gl_WorkGroupID.x];
    dvec4 acc = dvec4(0.0);
    for (uint e = local; e < segment.y; e += kWorkgroup1D) {
        uint j = elementAt(segment.x + e);
        acc.rgb += dvec3(x[j].rgb) * dvec3(y[j].rgb);
    }
    s_reduce[local] = acc;
    barrier();
    for (uint stride = kWorkgroup1D / 2; stride > 0; stride >>= 1) {
        if (local < stride) s_reduce[local] += s_reduce[local + stride];
        barrier();
    }
    if (local == 0) partial[gl_WorkGroupID.x] = s_reduce[0];
#elif VOLSTYLE_OP == VOLSTYLE_OP_LAPLACIAN
    if (inside) {
        ivec3 n = v.dims.xyz;
        int block = int(i) / v.count.z, cell = int(i) % v.count.z;
        ivec3 c = voxelOfCell(cell);
        vec3 sum = vec3(0.0);
        if (z[i].r > 0.0) {
            const ivec3 offsets[6] = ivec3[6](ivec3(1, 0, 0), ivec3(-1, 0, 0), ivec3(0, 1, 0),
                                              ivec3(0, -1, 0), ivec3(0, 0, 1), ivec3(0, 0, -1));
            for (int o = 0; o < 6; ++o) {
                ivec3 q = c + offsets[o];
                if (any(lessThan(q, ivec3(0))) || any(greaterThanEqual(q, n))) continue;
                uint j = uint(block * v.count.z + cellOfVoxel(q));
                if (z[j].r > 0.0) sum += x[j].rgb - x[i].rgb;
            }
        }
        y[i] = vec4(v.alpha.rgb * sum, 0.0);
    }
#elif VOLSTYLE_OP == VOLSTYLE_OP_FREE
    if (inside) {
        vec2 b = boundsOf(i);
        bvec3 atLower = lessThanEqual(x[i].rgb, vec3(b.x)), atUpper = greaterThanEqual(x[i].rgb, vec3(b.y));
        bvec3 fixedLower = bvec3(atLower.x && y[i].r < 0.0, atLower.y && y[i].g < 0.0, atLower.z && y[i].b < 0.0);
        bvec3 fixedUpper = bvec3(atUpper.x && y[i].r > 0.0, atUpper.y && y[i].g > 0.0, atUpper.z && y[i].b > 0.0);
        y[i].rgb = mix(y[i].rgb, vec3(0.0), bvec3(fixedLower.x || fixedUpper.x, fixedLower.y || fixedUpper.y,
                                                  fixedLower.z || fixedUpper.z));
    }
#elif VOLSTYLE_OP == VOLSTYLE_OP_STEP
    dvec4 t = dvec4(kNone);
    for (uint e = k; e < uint(v.count.x); e += gl_NumWorkGroups.x * kWorkgroup1D) {
        uint j = elementAt(e);
        vec2 b = boundsOf(j);
        vec3 a = x[j].rgb, p = y[j].rgb;
        t = min(t, dvec4(stepToBound(a.r, p.r, b), stepToBound(a.g, p.g, b), stepToBound(a.b, p.b, b), kNone));
    }
    s_reduce[local] = t;
    barrier();
    for (uint stride = kWorkgroup1D / 2; stride > 0; stride >>= 1) {
        if (local < stride) s_reduce[local] = min(s_reduce[local], s_reduce[local + stride]);
        barrier();
    }
    if (local == 0) partial[gl_WorkGroupID.x] = s_reduce[0];
#elif VOLSTYLE_OP == VOLSTYLE_OP_MAXCHANGE
    dvec4 m = dvec4(0.0);
    for (uint e = k; e < uint(v.count.x); e += gl_NumWorkGroups.x * kWorkgroup1D) {
        uint j = elementAt(e);
        m = max(m, dvec4(relativeChange(x[j].r, y[j].r, z[j].r), relativeChange(x[j].g, y[j].g, z[j].g),
                         relativeChange(x[j].b, y[j].b, z[j].b), 0.0lf));
    }
    s_reduce[local] = m;
    barrier();
    for (uint stride = kWorkgroup1D / 2; stride > 0; stride >>= 1) {
        if (local < stride) s_reduce[local] = max(s_reduce[local], s_reduce[local + stride]);
        barrier();
    }
    if (local == 0) partial[gl_WorkGroupID.x] = s_reduce[0];
#elif VOLSTYLE_OP == VOLSTYLE_OP_CLAMP
    if (inside) {
        vec2 b = boundsOf(i);
        y[i].rgb = clamp(y[i].rgb, vec3(b.x), vec3(b.y));
    }
#endif
}
