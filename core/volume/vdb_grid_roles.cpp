#include "core/volume/vdb_grid_roles.h"

#include "core/base/errors.h"

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
    if (digits == name.size()) return std::nullopt;
    // "density.-1": a frame number with a sign (once dropped in silence, with a 200).
    const bool negative = digits >= 2 && name[digits - 1] == '-' && (name[digits - 2] == '.' || name[digits - 2] == '_');
    const size_t sep = negative ? digits - 2 : digits - 1;
    if (digits < 2 || (name[sep] != '.' && name[sep] != '_') || sep == 0) return std::nullopt;
    if (negative || name.size() - digits > 6)  // "density.4294967301": once dropped, or wrapped to frame 5
        throw InvalidArgument("grid '" + name.substr(0, 80) + "' names frame " + name.substr(sep + 1, 24) +
                              ", outside 0.." + std::to_string(kMaxGridFrame) + " (frame numbers are whole, 0 or more)");
    return std::make_pair(std::stoi(name.substr(digits)), name.substr(0, sep));
}

}  // namespace volstyle::core::vdb_role
