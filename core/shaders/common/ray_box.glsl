// A ray o + t·d against an axis-aligned box: the slab test every march and brick skip uses.
// invD is safeInverse(d) (zero components nudged, so their slabs are all or nothing).

vec3 safeInverse(vec3 d) { return 1.0 / mix(d, vec3(1e-30), equal(d, vec3(0.0))); }

// (entry t, exit t) of the ray in [lo, hi]; it misses the box when x >= y.
vec2 rayBox(vec3 o, vec3 invD, vec3 lo, vec3 hi) {
    vec3 t0 = (lo - o) * invD, t1 = (hi - o) * invD;
    vec3 near = min(t0, t1), far = max(t0, t1);
    return vec2(max(near.x, max(near.y, near.z)), min(far.x, min(far.y, far.z)));
}
