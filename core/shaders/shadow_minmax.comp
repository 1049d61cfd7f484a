// The min-max mipmap of the scattering's shadow map (Chen et al. 2011's min-max idea, kept 2D so
// that no per-camera rectification is needed): entry (x, y) of level k + 1 holds the minimum and
// maximum depth of its 2×2 entries of level k; level 0 is the map itself (min = max = depth),
// and the coarser levels follow it in the same buffer (common/min_max_entry.glsl).
// Entries past a level's edge (odd sides) count as empty (depth 1: lit), which keeps every bound
// conservative. stylize.comp descends it to find the stretches of a view ray that are wholly lit
// or wholly in shadow.
#include "layout.h"
#include "common/min_max_entry.glsl"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(std140, binding = kBindingParams) uniform b_MinMaxParams {
    MinMaxParams m;
};
layout(std430, binding = kBindingMinMax) buffer b_MinMax {
    uint minMax[];  // level 0: the map's float depths; then the packed levels
};

void main() {
    ivec2 xy = ivec2(gl_GlobalInvocationID.xy);
    int src = m.level.x, dst = m.level.y;
    if (xy.x >= dst || xy.y >= dst) return;
    bool fromMap = m.level.z == 0;
    vec2 r = vec2(3.0e38, -3.0e38);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            ivec2 c = 2 * xy + ivec2(i, j);
            vec2 v = all(lessThan(c, ivec2(src))) ? minMaxOfEntry(minMax[m.level.z + c.y * src + c.x], fromMap) : vec2(1.0);
            r = vec2(min(r.x, v.x), max(r.y, v.y));
        }
    minMax[m.level.w + xy.y * dst + xy.x] = packMinMax16(r.x, r.y);
}
