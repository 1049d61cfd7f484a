#pragma once
/// \file glass_sphere.h
/// The parameters of a generated refractive-index grid (issue #16): a glass sphere with noise, as
/// in the TVCG paper's Fig. 8. GL-free value type; builtin_scenes.h's addGlassSphere() bakes it.

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace volstyle::core {

/// A glass sphere for refraction (issue #16, the TVCG paper's Fig. 8).
struct GlassSphere {
    double index = 1.33;        ///< n inside
    double radius = 0.55;       ///< world units, centred on the volume's box
    double edgeVoxels = 2;      ///< width of the smooth step from 1 to `index` at the surface
    double noise = 0.03;        ///< amplitude of the Perlin noise added to n inside
    double noiseFrequency = 3;  ///< of the noise, per world unit
    uint32_t seed = 1;

    /// Problems as (field, message), named as in the JSON API: index in [1, 4], radius in
    /// (0, 1e4], edge_voxels in [0.5, 64], noise in [0, index − 1] (n stays ≥ 1),
    /// noise_frequency in [0, 1e3].
    std::vector<std::pair<std::string, std::string>> check() const {
        std::vector<std::pair<std::string, std::string>> out;
        if (!(index >= 1 && index <= 4)) out.push_back({"index", "must be in [1, 4]"});
        if (!(radius > 0 && radius <= 1e4)) out.push_back({"radius", "must be in (0, 1e4] world units"});
        if (!(edgeVoxels >= 0.5 && edgeVoxels <= 64)) out.push_back({"edge_voxels", "must be in [0.5, 64]"});
        if (!(noise >= 0 && noise <= std::max(index - 1, 0.0)))
            out.push_back({"noise", "must be in [0, index - 1] (the index stays at least 1)"});
        if (!(noiseFrequency >= 0 && noiseFrequency <= 1e3)) out.push_back({"noise_frequency", "must be in [0, 1000] per world unit"});
        return out;
    }
};
}  // namespace volstyle::core
