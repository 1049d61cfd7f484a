// atan2 to float precision. GLSL leaves the accuracy of atan unspecified and llvmpipe's is off by
// ~1e-3 rad, which shifts environment-map lookups by a visible fraction of a texel.

const float kPi = 3.14159265358979;

// atan(t) for |t| <= 1: reduce past tan(π/8) with atan(t) = π/4 + atan((t−1)/(t+1)), halve once
// with atan(t) = 2 atan(t / (1 + sqrt(1 + t²))), then a Taylor series to t^11 (|t| < 0.2: < 2e-9).
float atanUnit(float t) {
    float offset = 0.0;
    if (t > 0.41421356) {
        offset = 0.25 * kPi;
        t = (t - 1.0) / (t + 1.0);
    } else if (t < -0.41421356) {
        offset = -0.25 * kPi;
        t = (t + 1.0) / (1.0 - t);
    }
    t = t / (1.0 + sqrt(1.0 + t * t));
    float t2 = t * t;
    float series = t * (1.0 + t2 * (-1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (-1.0 / 7.0 + t2 * (1.0 / 9.0 - t2 / 11.0)))));
    return offset + 2.0 * series;
}

float preciseAtan2(float y, float x) {
    if (x == 0.0 && y == 0.0) return 0.0;
    if (abs(x) >= abs(y)) {
        float a = atanUnit(y / x);
        return x > 0.0 ? a : (y >= 0.0 ? a + kPi : a - kPi);
    }
    float a = atanUnit(x / y);
    return y > 0.0 ? 0.5 * kPi - a : -0.5 * kPi - a;
}
