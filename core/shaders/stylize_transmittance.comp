// The heterogeneous medium's optical depth toward the stylizer's light (issue #15), per voxel of
// its σt grid: τ_l(x) = ∫ σt from the voxel's centre to where the ray toward the light leaves the
// box (or reaches the spot), by the midpoint rule at half the smallest voxel side. stylize.comp
// interpolates τ_l trilinearly and takes T_l = e^{−τ_l} (inside V̄ and on surfaces): the optical
// depth varies smoothly where the transmittance falls off exponentially inside a dense layer, so
// interpolating it, not T_l, keeps a slab's shadow within 1% of the exact integral.
#include "common/stylize_medium.glsl"
#include "common/ray_box.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;

layout(r32f, binding = kImageUnitOut) writeonly uniform image3D o_opticalDepth;

void main() {
    ivec3 n = textureSize(s_density, 0);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, n))) return;
    vec3 lo = u.volumeLo.xyz, size = u.volumeHi.xyz - u.volumeLo.xyz;
    vec3 x = lo + (vec3(v) + 0.5) / vec3(n) * size;
    vec3 l;
    float length_ = 3.0e38;
    if (u.options.z == kStylizerLightSpot) {
        vec3 toLight = u.spot.xyz - x;
        length_ = length(toLight);
        l = toLight / max(length_, 1e-30);
    } else {
        l = u.lightDirection.xyz;
    }
    // Where the ray toward the light leaves the box.
    length_ = max(min(length_, rayBox(x, safeInverse(l), lo, u.volumeHi.xyz).y), 0.0);
    float step = 0.5 * min(size.x / float(n.x), min(size.y / float(n.y), size.z / float(n.z)));
    int k = clamp(int(ceil(length_ / step)), 1, 4096);
    float dt = length_ / float(k), tau = 0.0;
    for (int i = 0; i < k; ++i) tau += densityAt((x + (float(i) + 0.5) * dt * l - lo) / size) * dt;
    imageStore(o_opticalDepth, v, vec4(tau));
}
