// Hole creation on one occluder's shadow map (the GI paper Sec. 4.2, Eq. 4): where the noise N of
// hole_noise.h falls below the threshold h, H = 1 and the depth is pushed to 1 (nothing there), in
// place. h is calibrated on the CPU so that the share of holes is the user's probability; the
// noise coordinates are world units across the light's beams times the frequency, so holes stay on
// the object whatever the map's fit or size.
#include "layout.h"
#include "hole_noise.h"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(std140, binding = kBindingParams) uniform b_EditParams {
    EditParams m;
};
layout(std430, binding = kBindingEditOut) buffer b_Depth {
    float depth[];
};

void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    int n = m.size.x;
    if (t.x >= n || t.y >= n) return;
    int i = t.y * n + t.x;
    if (depth[i] >= 1.0) return;
    vec2 q = m.holeFrame.xy + (vec2(t) + 0.5) * m.holeFrame.zw;
    if (holeNoise(q.x, q.y, m.holeNoise.z, m.holeNoise.w, m.size.z, m.holeNoise.y, uint(m.size.w)) < m.holeNoise.x) depth[i] = 1.0;
}
