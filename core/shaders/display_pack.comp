// A frame's display bytes on the GPU (issue #40): the live stream reads back a quarter of the
// frame's float bytes and the CPU encodes them without converting. As core::displayBytes (and a
// PNG): linear × 2^exposure, clamped to [0, 1] (NaN: black), sRGB-encoded, rounded to 8 bits.
#include "layout.h"

layout(local_size_x = kWorkgroup2D, local_size_y = kWorkgroup2D) in;

layout(std140, binding = kBindingParams) uniform DisplayPackBlock { DisplayPackParams u; };
layout(std430, binding = kBindingImageOut) readonly buffer b_Image { vec4 pixels[]; };
layout(std430, binding = kBindingDisplayOut) writeonly buffer b_Display { uint display[]; };

float srgb(float v) {
    v = v > 0.0 ? min(v * u.scale.x, 1.0) : 0.0;  // NaN > 0 is false: black
    return v <= 0.0031308 ? v * 12.92 : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= u.size.x || px.y >= u.size.y) return;
    uint i = uint(px.y) * uint(u.size.x) + uint(px.x);  // rows as the frame's: top first
    vec4 c = pixels[i];
    display[i] = packUnorm4x8(vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0));  // R in the lowest byte: R, G, B, 255 in memory
}
