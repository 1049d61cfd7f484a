// The stylizer's σt grid from the session's volume on the GPU (issue #36): the mean of its RGB
// extinction per voxel, as one channel (r32f). Made once per extinction version and kept in the
// device's cache. The march could read the RGB texture itself, but on a CPU rasterizer its three
// times larger footprint made a 960×540 frame through the built-in 64³ cloud 10–15% slower
// (docs/BENCHMARKS.md, issue #36); one channel matches the old frame time.
#include "common/stylize_params.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;

layout(binding = kUnitStylizeDensity) uniform sampler3D s_extinctionRgb;
layout(r32f, binding = kImageUnitOut) writeonly uniform image3D o_sigma;

void main() {
    ivec3 n = textureSize(s_extinctionRgb, 0);
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, n))) return;
    vec3 e = texelFetch(s_extinctionRgb, v, 0).rgb;
    imageStore(o_sigma, v, vec4((e.r + e.g + e.b) / 3.0));
}
