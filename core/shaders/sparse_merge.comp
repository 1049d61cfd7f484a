// Appends one view's columns (core/solve/sparse_rows.h) to the columns of every cached view at
// once (Projector::mergeRows): element e's entries go after those of the views merged before it
// (colCursor), their pixels offset by the view's first pixel. With the rows concatenated on the
// host side, W and Wᵀ of all views are then one gather each instead of one per view (llvmpipe
// pays ~0.35 ms a dispatch: 60 views of the CT slice spent most of an iteration on them).
// The view's columns come in on the row bindings (this pass writes no rows).
#include "layout.h"

#ifndef VOLSTYLE_ROW_CHANNELS
#define VOLSTYLE_ROW_CHANNELS 3
#endif

layout(local_size_x = kWorkgroup1D) in;

layout(std140, binding = kBindingParams) uniform b_SparseParams {
    SparseParams sp;  // count.x: elements; count.y: the view's first pixel
};
layout(std430, binding = kBindingRowStart) readonly buffer b_ViewStart {
    uint viewStart[];
};
layout(std430, binding = kBindingRowIndex) readonly buffer b_ViewIndex {
    uint viewIndex[];
};
layout(std430, binding = kBindingRowWeight) readonly buffer b_ViewWeight {
    float viewWeight[];
};
layout(std430, binding = kBindingColStart) readonly buffer b_ColStart {
    uint colStart[];
};
layout(std430, binding = kBindingColCursor) buffer b_ColCursor {
    uint colCursor[];
};
layout(std430, binding = kBindingColIndex) writeonly buffer b_ColIndex {
    uint colIndex[];
};
layout(std430, binding = kBindingColWeight) writeonly buffer b_ColWeight {
    float colWeight[];
};

void main() {
    uint e = gl_GlobalInvocationID.x;
    if (e >= uint(sp.count.x)) return;
    uint first = viewStart[e], last = viewStart[e + 1u];
    uint to = colStart[e] + colCursor[e];
    for (uint k = first; k < last; ++k, ++to) {
        colIndex[to] = viewIndex[k] + uint(sp.count.y);
        for (uint c = 0u; c < uint(VOLSTYLE_ROW_CHANNELS); ++c)
            colWeight[uint(VOLSTYLE_ROW_CHANNELS) * to + c] = viewWeight[uint(VOLSTYLE_ROW_CHANNELS) * k + c];
    }
    colCursor[e] += last - first;
}
