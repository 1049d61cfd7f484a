// The pinhole camera's ray through a pixel centre (SPEC §1; row 0 at the top), from the camera
// fields both parameter blocks carry: forward.w = tan(fov_y / 2), right.w = width / height.
vec3 pinholeRay(ivec2 pix, ivec2 size, vec4 forward, vec4 right, vec3 up) {
    vec2 ndc = (vec2(pix) + 0.5) / vec2(size) * 2.0 - 1.0;
    float tanHalf = forward.w, aspect = right.w;
    return normalize(forward.xyz + right.xyz * (ndc.x * tanHalf * aspect) - up * (ndc.y * tanHalf));
}
