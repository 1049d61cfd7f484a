// One pass of grey-scale morphology on a shadow map (the GI paper Sec. 4.1: a dilation replaces a
// depth by the minimum over the structuring element, an erosion by the maximum; a closing is a
// dilation then an erosion): the extremum over the 1D window [x − w, x + w] of every row (or
// column), at a cost per texel that does not depend on w (van Herk 1992, Gil & Werman 1993):
// with blocks of k = 2w + 1 texels, g is the running extremum from each block's start and h to
// each block's end, and window [x − w, x + w] is op(h[x − w], g[x + w]). Texels outside the map are
// empty (depth 1, no occluder): the stylizer keeps occluders a closing radius away from the
// border, so that neither operation sees past it. One invocation per line, three sweeps.
// Line offset dy (size.w): the window is taken on line y + dy and written to line y (the disc's
// rows); op.y = 1 folds the result into the output instead of overwriting it.
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
    int n = m.size.x, w = m.size.y;
    int line = int(gl_GlobalInvocationID.x);
    if (line >= n) return;
    bool columns = m.size.z == 1;
    int source = line + m.size.w;  // the line the window is read from
    const float neutral = 1.0;  // outside the map: nothing occludes
    int k = 2 * w + 1, len = n + 2 * w;
    int gBase = 2 * line * len, hBase = gBase + len;
    // value(v) for virtual index v ∈ [0, len): texel v − w of the source line, or neutral.
    #define VALUE(v) ((source >= 0 && source < n && (v) - w >= 0 && (v) - w < n) ? \
        depthIn[columns ? ((v) - w) * n + source : source * n + ((v) - w)] : neutral)
    for (int v = 0; v < len; ++v) scratch[gBase + v] = (v % k == 0) ? VALUE(v) : combine(scratch[gBase + v - 1], VALUE(v));
    for (int v = len - 1; v >= 0; --v)
        scratch[hBase + v] = (v % k == k - 1 || v == len - 1) ? VALUE(v) : combine(scratch[hBase + v + 1], VALUE(v));
    for (int x = 0; x < n; ++x) {
        float r = combine(scratch[hBase + x], scratch[gBase + x + 2 * w]);
        int index = columns ? x * n + line : line * n + x;
        depthOut[index] = m.op.y == 1 ? combine(depthOut[index], r) : r;
    }
}
