// The min-max mipmap of the scattering's shadow map (Chen et al. 2011's min-max idea, kept 2D so
// that no per-camera rectification is needed): entry (x, y) of level k + 1 holds the minimum and
// maximum depth of its 2×2 entries of level k; level 0 is the map itself (min = max = depth).
// Entries past a level's edge (odd sides) count as empty (depth 1: lit), which keeps every bound
// conservative. stylize.comp descends it to find the stretches of a view ray that are wholly lit
// or wholly in shadow.
#include "layout.h"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(std140, binding = kBindingParams) uniform b_MinMaxParams {
    MinMaxParams m;
};
layout(std430, binding = kBindingScatterDepth) readonly buffer b_Depth {
    float depth[];  // level 0's source
};
layout(std430, binding = kBindingMinMax) buffer b_MinMax {
    vec2 minMax[];
};

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    int src = m.level.x, dst = m.level.y;
    if (xy.x >= dst || xy.y >= dst) return;
    if (m.level.z < 0) {  // level 0: copy the map
        float d = depth[xy.y * dst + xy.x];
        minMax[m.level.w + xy.y * dst + xy.x] = vec2(d);
        return;
    }
    vec2 r = vec2(3.0e38, -3.0e38);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            ivec2 c = 2 * xy + ivec2(i, j);
            vec2 v = all(lessThan(c, ivec2(src))) ? minMax[m.level.z + c.y * src + c.x] : vec2(1.0);
            r = vec2(min(r.x, v.x), max(r.y, v.y));
        }
    minMax[m.level.w + xy.y * dst + xy.x] = r;
}
