// The solver's operator from its cached rows (core/solve/sparse_rows.h), one source for both:
// VOLSTYLE_ADJOINT = 0 gathers each pixel's row, (W a)_p = Σ_k w_k a[e_k]; = 1 gathers each
// unknown's column of the same entries, (Wᵀ r)_e += Σ_k w_k r[p_k] — a gather, so no atomics,
// and every element is written by one invocation. The entries are the ones project.comp's
// VOLSTYLE_ROWS passes wrote from the same rays, so both agree with the matrix-free operator to
// float rounding (the sums run in another order). VOLSTYLE_MARK = 1 reads no values: every entry
// of the listed rows (or columns) sets its element (or pixel) to 1 — which unknowns a set of pixels
// sees, and which pixels see a set of unknowns (the solver's local re-solve, solver_local.cpp).
// VOLSTYLE_SCATTER = 1 applies W by columns to a mostly-zero c (Projector::forwardByColumns).
#include "layout.h"

#ifndef VOLSTYLE_MARK
#define VOLSTYLE_MARK 0
#endif

#ifndef VOLSTYLE_ADJOINT
#define VOLSTYLE_ADJOINT 0
#endif
#ifndef VOLSTYLE_ROW_CHANNELS
#define VOLSTYLE_ROW_CHANNELS 3
#endif

layout(local_size_x = kWorkgroup1D) in;

layout(std140, binding = kBindingParams) uniform b_SparseParams {
    SparseParams sp;
};
layout(std430, binding = kBindingSparseIn) readonly buffer b_In {
    vec4 inputs[];
};
#ifndef VOLSTYLE_SCATTER
#define VOLSTYLE_SCATTER 0
#endif
#ifndef VOLSTYLE_HAS_FLOAT_ATOMICS
#define VOLSTYLE_HAS_FLOAT_ATOMICS 0
#endif
#if VOLSTYLE_SCATTER
// W c by columns, for a c that is 0 almost everywhere (what a bound clamped in a projected step):
// only the non-zero elements' columns are read, their entries added to the pixels atomically.
#if VOLSTYLE_HAS_FLOAT_ATOMICS
layout(std430, binding = kBindingSparseOut) buffer b_Out {
    float outputs[];
};
void scatterAdd(uint i, float v) { atomicAdd(outputs[i], v); }
#else
// No float atomics (core GL 4.5 has none): a compare-and-swap loop on the bits.
layout(std430, binding = kBindingSparseOut) buffer b_Out {
    uint outputBits[];
};
void scatterAdd(uint i, float v) {
    uint seen = outputBits[i];
    for (;;) {
        uint expected = seen;
        seen = atomicCompSwap(outputBits[i], expected, floatBitsToUint(uintBitsToFloat(expected) + v));
        if (seen == expected) break;
    }
}
#endif
#else
layout(std430, binding = kBindingSparseOut) buffer b_Out {
    vec4 outputs[];
};
#endif
layout(std430, binding = kBindingSparseStart) readonly buffer b_Start {
    uint start[];
};
layout(std430, binding = kBindingSparseIndex) readonly buffer b_Index {
    uint index[];
};
layout(std430, binding = kBindingSparseWeight) readonly buffer b_Weight {
    float weight[];
};
layout(std430, binding = kBindingSparseList) readonly buffer b_List {
    uint list[];  // the solver's constrained pixels (W) or hull elements (Wᵀ): the rest are never read
};

vec3 weightOf(uint k) {
#if VOLSTYLE_ROW_CHANNELS == 1
    return vec3(weight[k]);
#else
    return vec3(weight[3u * k], weight[3u * k + 1u], weight[3u * k + 2u]);
#endif
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= uint(sp.count.x)) return;
    // Row or column i of this view's cache, written at output o.
    uint o = sp.count.w >= 0 ? list[uint(sp.count.w) + k] : uint(sp.count.z) + k;
    uint i = o - uint(sp.count.z) + uint(sp.range.x);  // merged rows: a view's row is its pixel
    uint first = start[i], last = start[i + 1u];
    uint inputOffset = uint(sp.count.y);
#if VOLSTYLE_SCATTER
    // Column o of the unknowns c (inputs); its pixels (after the output offset) receive w · c.
    vec3 c = inputs[o].rgb;
    if (c == vec3(0.0)) return;
    uint outputOffset = uint(sp.count.y);
    for (uint e = first; e < last; ++e) {
        vec3 v = weightOf(e) * c;
        uint q = 4u * (outputOffset + index[e]);
        scatterAdd(q, v.r);
        scatterAdd(q + 1u, v.g);
        scatterAdd(q + 2u, v.b);
    }
#elif VOLSTYLE_MARK
    for (uint e = first; e < last; ++e)  // races store the same value; unfilled slots (weight 0) mark nothing
        if (any(notEqual(weightOf(e), vec3(0.0)))) outputs[inputOffset + index[e]] = vec4(1.0);
#else
    vec3 sum = vec3(0.0);
#if VOLSTYLE_ADJOINT
    // One view of merged columns: its pixels' entries alone (every view's lie in the same list).
    uint lo = uint(sp.range.y), hi = uint(sp.range.z);
    for (uint e = first; e < last; ++e)
        if (index[e] >= lo && index[e] < hi) sum += weightOf(e) * inputs[inputOffset + index[e]].rgb;
#else
    for (uint e = first; e < last; ++e) sum += weightOf(e) * inputs[inputOffset + index[e]].rgb;
#endif
#if VOLSTYLE_ADJOINT
    if (first != last) outputs[o] += vec4(sum, 0.0);  // the views' columns add up, one dispatch each
#else
    outputs[o] = vec4(sum, 0.0);
#endif
#endif
}
