// Phase functions (SPEC §1): isotropic 1/4π, or Henyey–Greenstein in pbrt's convention
// (cosTheta = ω_l·(−ω), g > 0 scatters forward). `type` < 0.5 selects isotropic.
const float kInvFourPi = 0.07957747154594767;

float phaseValue(float type, float g, float cosTheta) {
    if (type < 0.5) return kInvFourPi;
    float denom = 1.0 + g * g + 2.0 * g * cosTheta;
    return kInvFourPi * (1.0 - g * g) / (denom * sqrt(max(denom, 1e-12)));
}
