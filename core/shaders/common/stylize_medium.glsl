// The stylizer's heterogeneous medium (issue #15; issue #36: the session's own GpuVolume): σt =
// extinction_scale × the mean of the volume's RGB extinction (stylize_extinction_mean.comp makes
// that grid on the GPU from the volume's texture), stretched over the box [u.volumeLo,
// u.volumeHi] (its voxels' box maps onto it). Trilinear between voxel centres and clamped to the
// edge voxels inside the box, as core::Volume samples.
#include "common/stylize_params.glsl"

layout(binding = kUnitStylizeDensity) uniform sampler3D s_density;  // the mean of the volume's RGB σt

// Grid coordinates of world point x ([0, 1]³ over the box).
vec3 volumeUvw(vec3 x) { return (x - u.volumeLo.xyz) / (u.volumeHi.xyz - u.volumeLo.xyz); }

// σt at grid coordinates uvw.
float densityAt(vec3 uvw) {
    return u.volumeScale.x * texture(s_density, uvw).r;
}
