// One pass of grey-scale morphology on a shadow map (the GI paper Sec. 4.1: a dilation replaces a
// depth by the minimum over the structuring element, an erosion by the maximum; a closing is a
// dilation then an erosion): the extremum over the 1D window [x − w, x + w] of every row (or
// column), at a cost per texel that does not depend on w (van Herk 1992, Gil & Werman 1993):
// with blocks of k = 2w + 1 texels, g is the running extremum from each block's start and h to
// each block's end, and window [x − w, x + w] is op(h[x − w], g[x + w]). Texels outside the map are
// empty (depth 1, no occluder): the stylizer keeps occluders a closing radius away from the
// border, so that neither operation sees past it. One invocation per line, three sweeps.
// Lines (size.z): 0 rows, 1 columns, 2 diagonals (step (1, 1)), 3 anti-diagonals (step (1, −1));
// there are 2n − 1 of each diagonal kind, of lengths 1…n, dispatched in parts (op.z: the first
// line of this part; the scratch holds one part). Line offset dy (size.w, rows only): the window
// is taken on row y + dy and written to row y (the small discs' rows); op.y = 1 folds the result
// into the output instead of overwriting it.
#include "layout.h"

layout(local_size_x = kWorkgroup1D) in;

layout(std140, binding = kBindingParams) uniform b_MorphParams {
    MorphParams m;
};
layout(std430, binding = kBindingMorphIn) readonly buffer b_In {
    float depthIn[];
};
layout(std430, binding = kBindingMorphOut) buffer b_Out {
    float depthOut[];
};
layout(std430, binding = kBindingMorphScratch) buffer b_Scratch {
    float scratch[];
};

float combine(float a, float b) { return m.op.x == 0 ? min(a, b) : max(a, b); }

void main() {
    int n = m.size.x, w = m.size.y, mode = m.size.z;
    int local = int(gl_GlobalInvocationID.x);
    int line = local + m.op.z;
    if (line >= (mode < 2 ? n : 2 * n - 1)) return;
    // The line: its first texel (x0, y0), its step (sx, sy), its length, and for rows the row
    // the window is read from.
    int x0 = 0, y0 = 0, sx = 1, sy = 0, length = n, source = line;
    if (mode == 0) {
        y0 = line;
        source = line + m.size.w;
    } else if (mode == 1) {
        x0 = line, sx = 0, sy = 1;
    } else if (mode == 2) {  // x − y = line − (n − 1)
        int d = line - (n - 1);
        x0 = max(0, d), y0 = x0 - d, sy = 1, length = n - abs(d);
    } else {  // x + y = line
        x0 = max(0, line - (n - 1)), y0 = line - x0, sy = -1, length = n - abs(line - (n - 1));
    }
    bool sourceInside = mode != 0 || (source >= 0 && source < n);
    int sourceY0 = mode == 0 ? source : y0;
    const float neutral = 1.0;  // outside the map: nothing occludes
    int k = 2 * w + 1, len = length + 2 * w, stride = n + 2 * w;
    int gBase = 2 * local * stride, hBase = gBase + stride;
    // value(v) for virtual index v ∈ [0, len): texel v − w of the source line, or neutral.
    #define VALUE(v) ((sourceInside && (v) - w >= 0 && (v) - w < length) ? \
        depthIn[(sourceY0 + ((v) - w) * sy) * n + x0 + ((v) - w) * sx] : neutral)
    for (int v = 0; v < len; ++v) scratch[gBase + v] = (v % k == 0) ? VALUE(v) : combine(scratch[gBase + v - 1], VALUE(v));
    for (int v = len - 1; v >= 0; --v)
        scratch[hBase + v] = (v % k == k - 1 || v == len - 1) ? VALUE(v) : combine(scratch[hBase + v + 1], VALUE(v));
    for (int t = 0; t < length; ++t) {
        float r = combine(scratch[hBase + t], scratch[gBase + t + 2 * w]);
        int index = (y0 + t * sy) * n + x0 + t * sx;
        depthOut[index] = m.op.y == 1 ? combine(depthOut[index], r) : r;
    }
}
