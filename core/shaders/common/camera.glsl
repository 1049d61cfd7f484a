// Pinhole camera rays (SPEC §1): through pixel centres, row 0 at the top.
#include "common/march.glsl"
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

#if VOLSTYLE_CURVED
// Pixel pix's path: its vertices' span in the path buffers.
ivec2 pathOf(ivec2 pix) {
    int p = pix.y * u.imageSize.x + pix.x;
    return ivec2(pathStart[p], pathStart[p + 1]);
}
#endif

// The march of pixel pix's view ray (world direction dir), straight or along its refracted
// path (common/march.glsl); false when it misses the volume.
bool beginViewMarch(ivec2 pix, vec3 dir, out RayMarch m) {
#if VOLSTYLE_CURVED
    ivec2 span = pathOf(pix);
    m = RayMarch(vec3(0.0), vec3(0.0), vec3(0.0), Segments(0.0, 0.0, 0), 0, 0.0, 0.0, true, 0, 0, 0.0, 0.0, span.x, span.y - 1, u.rayRange.xy, dir);
    return m.lastVertex > m.vertex;  // no piece yet: the first nextSegment() starts one
#else
    vec3 o, d;
    vec2 range;
    viewRay(dir, o, d, range);
    m = beginMarch(range, o, d);  // set even when unused: the compiler sees m written on every path
    return range.x < range.y;
#endif
}

// The direction pixel pix's ray leaves in (for the background): carried from the tracer
// (curved_paths.h ViewPaths::exitDirection), not differenced from the last piece's two ends.
vec3 exitDirection(ivec2 pix, vec3 dir) {
#if VOLSTYLE_CURVED
    vec4 exit = pathExit[pix.y * u.imageSize.x + pix.x];
    if (exit.w > 0.0) return exit.xyz;
#endif
    return dir;
}
