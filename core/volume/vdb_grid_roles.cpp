#include "core/volume/vdb_grid_roles.h"

#include <cctype>

namespace volstyle::core::vdb_role {

std::vector<std::string> roleNames(Role role) {
    switch (role) {
        case kExtinction: return {"extinction", "density"};
        case kAlbedo: return {"albedo"};
        case kEmission: return {"emission"};
        default: return {"refractive_index"};
    }
}

float absentValue(Role role) {
    return role == kAlbedo ? kDefaultAlbedo : role == kRefractiveIndex ? 1.0f : 0.0f;
}

std::vector<float> denseOfVolume(const Volume& v, Role role) {
    switch (role) {
        case kExtinction: return v.extinction();
        case kAlbedo: return v.albedo();
        case kEmission: return v.emission();
        default: {
            std::vector<float> rgb;
            if (!v.refractiveIndex()) return rgb;
            rgb.reserve(v.voxelCount() * 3);
            for (float n : *v.refractiveIndex()) rgb.insert(rgb.end(), {n, n, n});
            return rgb;
        }
    }
}

std::optional<std::pair<int, std::string>> frameOfGridName(const std::string& name) {
    size_t digits = name.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(name[digits - 1]))) --digits;
    if (digits == name.size() || digits < 2 || (name[digits - 1] != '.' && name[digits - 1] != '_') || name.size() - digits > 6) return std::nullopt;
    return std::make_pair(std::stoi(name.substr(digits)), name.substr(0, digits - 1));
}

}  // namespace volstyle::core::vdb_role
