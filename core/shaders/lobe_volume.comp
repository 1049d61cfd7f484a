// One environment lobe's light volume (core/render/lobe_volumes.h): at every node of the light
// volumes' grid, the transmittance toward lobe u.lobeKernel.x, e^{−τ} with τ the optical depth
// interpolated from the lobe's light-depth grid (light_depth.comp, bound as light 0). Node j sits
// at extinction index (j + 0.5)/scale − 0.5, so both grids span the voxels' box.
#include "common/volume.glsl"

layout(local_size_x = kWorkgroup3D, local_size_y = kWorkgroup3D, local_size_z = kWorkgroup3D) in;

layout(binding = kUnitLightDepth0) uniform sampler3D s_lobeDepth;
layout(binding = kImageUnitOut, r32f) uniform writeonly imageBuffer img_lobeTransmittance;

void main() {
    ivec3 node = ivec3(gl_GlobalInvocationID) + u.dispatchOffset.xyz;  // chunked_dispatch.h
    ivec3 n = u.lobeGrid.xyz;
    if (any(greaterThanEqual(node, n))) return;
    vec3 p = (vec3(node) + 0.5) / u.lobeScale.xyz - 0.5;
    vec3 g = (u.lightGridFromIndex[0] * vec4(p, 1.0)).xyz;
    vec3 transmittance = exp(-fetchTrilinear(s_lobeDepth, stencilOn(g, u.lightGridDims[0].xyz)));
    int channels = int(u.lobeScale.w);
    int base = (((node.z * n.y + node.y) * n.x + node.x) * u.lobeGrid.w + u.lobeKernel.x) * channels;
    imageStore(img_lobeTransmittance, base, vec4(transmittance.r));
    if (channels == 3) {
        imageStore(img_lobeTransmittance, base + 1, vec4(transmittance.g));
        imageStore(img_lobeTransmittance, base + 2, vec4(transmittance.b));
    }
}
