// Pinhole camera rays (SPEC §1): through pixel centres, row 0 at the top.
#include "common/volume.glsl"
#include "common/pinhole.glsl"

vec3 cameraRay(ivec2 pix) { return pinholeRay(pix, u.imageSize.xy, u.camForward, u.camRight, u.camUp.xyz); }

// The view ray of `dir` in index space (o + t d, t in world units) and its span inside the
// volume box, clipped to [near, far].
void viewRay(vec3 dir, out vec3 o, out vec3 d, out vec2 range) {
    o = (u.indexFromWorld * vec4(u.eye.xyz, 1.0)).xyz;
    d = mat3(u.indexFromWorld) * dir;
    range = intersectVolumeBox(o, d);
    range = vec2(max(range.x, u.rayRange.x), min(range.y, u.rayRange.y));
}
