// The stylizer's heterogeneous medium (issue #15; issue #36: the session's own GpuVolume): the
// volume's RGB extinction texture, stretched over the box [u.volumeLo, u.volumeHi] (its voxels'
// box maps onto it), with σt = extinction_scale × the mean of the three channels. Trilinear
// between voxel centres and clamped to the edge voxels inside the box, as core::Volume samples.
#include "common/stylize_params.glsl"

layout(binding = kUnitStylizeDensity) uniform sampler3D s_density;  // the volume's RGB σt

// Grid coordinates of world point x ([0, 1]³ over the box).
vec3 volumeUvw(vec3 x) { return (x - u.volumeLo.xyz) / (u.volumeHi.xyz - u.volumeLo.xyz); }

// σt at grid coordinates uvw.
float densityAt(vec3 uvw) {
    vec3 e = texture(s_density, uvw).rgb;
    return u.volumeScale.x * ((e.r + e.g + e.b) / 3.0);
}
