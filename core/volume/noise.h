#pragma once
/// \file noise.h
/// Deterministic Perlin gradient noise ("improved noise", Perlin 2002) and fractal sums, used by
/// the built-in scenes to perturb implicit shapes (Kniss et al. 2003, Sec. 3.4). The permutation
/// comes from a fixed-seed std::mt19937, whose output sequence the C++ standard fixes, so scenes
/// are identical on every machine.

#include <array>
#include <cstdint>

#include "core/math/vec.h"

namespace volstyle::core {

class PerlinNoise {
public:
    explicit PerlinNoise(uint32_t seed = 1);
    /// Noise in about [-1, 1], zero at integer lattice points.
    double operator()(const Vec3d& p) const;
    /// Fractal Brownian motion: Σ gain^o · noise(p · lacunarity^o), normalised to about [-1, 1].
    double fbm(const Vec3d& p, int octaves, double lacunarity = 2.0, double gain = 0.5) const;
    /// Three decorrelated fbm channels: a displacement field.
    Vec3d fbm3(const Vec3d& p, int octaves) const;

private:
    std::array<uint8_t, 512> m_perm;
};

}  // namespace volstyle::core
