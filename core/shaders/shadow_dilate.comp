// The 1D epipolar dilation of one occluder's shadow map (the GI paper Sec. 4.1, Eq. 3, Fig. 4):
// every texel t looks at the samples s on the line from t toward the epipole l (the camera
// projected into the map), up to m.size.y texels but never past l, and takes
//   z_t' = min(z_t, min_s (dis(t, l) / dis(s, l)) (z_s − z_l) + z_l),
// the depth the view ray through s has when it passes over t: occluders are extruded along the
// camera's rays, away from it, so the new blockers hide behind the object itself. Empty samples
// (depth 1) extrude nothing; results are clamped to the map's [0, 1].
#include "layout.h"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(std140, binding = kBindingParams) uniform b_EditParams {
    EditParams m;
};
layout(std430, binding = kBindingEditIn) readonly buffer b_In {
    float depthIn[];
};
layout(std430, binding = kBindingEditOut) writeonly buffer b_Out {
    float depthOut[];
};

void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    int n = m.size.x;
    if (t.x >= n || t.y >= n) return;
    float best = depthIn[t.y * n + t.x];
    vec2 pt = vec2(t) + 0.5, l = m.epipole.xy;
    float dist = distance(pt, l), zl = m.epipole.z;
    if (dist > 1e-3) {
        vec2 stepDir = (l - pt) / dist * m.epipole.w;  // one texel toward the epipole (away: camera behind a spot)
        int kernel = m.epipole.w > 0.0 ? min(m.size.y, int(dist)) : m.size.y;
        for (int k = 1; k <= kernel; ++k) {
            vec2 ps = pt + float(k) * stepDir;
            ivec2 s = ivec2(floor(ps));
            if (any(lessThan(s, ivec2(0))) || any(greaterThanEqual(s, ivec2(n)))) break;
            float zs = depthIn[s.y * n + s.x];
            if (zs >= 1.0) continue;
            float ds = max(distance(ps, l), 1e-3);
            best = min(best, clamp(dist / ds * (zs - zl) + zl, 0.0, 1.0));
        }
    }
    depthOut[t.y * n + t.x] = best;
}
