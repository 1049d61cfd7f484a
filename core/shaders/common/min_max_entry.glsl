// One entry of the shadow map's min-max mipmap (shadow_minmax.comp, read by stylize.comp). The
// pyramid lives in the scattering's depth buffer itself, after the map: level 0 is the map's own
// float depth (exact, min = max), every coarser level packs (min, max) as two 16-bit fixed-point
// numbers in one uint, min rounded down and max rounded up, so a coarse bound only ever widens
// (never decides wrongly) and the walk reads 4 bytes per step, not 8. Depth 1 (nothing drawn)
// stays exactly 1.
// 1/65535 rounded to nearest, by its bits rather than by a compiler's constant folding: with it
// 65535 · kDepthStep is exactly 1.0, so code 65535 unpacks to "nothing drawn" with no compare.
const float kDepthStep = uintBitsToFloat(0x37800080u);

float unpackDepth16(uint q) { return float(q) * kDepthStep; }

vec2 minMaxOfEntry(uint bits, bool level0) {
    if (level0) return vec2(uintBitsToFloat(bits));
    return vec2(unpackDepth16(bits & 0xffffu), unpackDepth16(bits >> 16));
}

// The 16-bit bounds of [lo, hi] (in [0, 1]): the largest code not above lo, the smallest not below hi.
uint packMinMax16(float lo, float hi) {
    uint a = uint(clamp(floor(lo * 65535.0), 0.0, 65535.0)), b = uint(clamp(ceil(hi * 65535.0), 0.0, 65535.0));
    while (a > 0u && unpackDepth16(a) > lo) --a;
    while (b < 65535u && unpackDepth16(b) < hi) ++b;
    return a | (b << 16);
}
