#include "cli/scene_source.h"

#include "core/base/errors.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"

namespace volstyle::cli {

core::Volume loadScene(const std::string& source, const core::VolumeLimits& limits) {
    const std::string prefix = "builtin:";
    if (source.rfind(prefix, 0) != 0) return core::loadVdb(source, limits);
    std::string rest = source.substr(prefix.size());
    std::string name = rest;
    int resolution = core::kDefaultSceneResolution;
    if (auto colon = rest.find(':'); colon != std::string::npos) {
        name = rest.substr(0, colon);
        const std::string res = rest.substr(colon + 1);
        size_t used = 0;
        try {
            resolution = std::stoi(res, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != res.size())
            throw InvalidArgument("scene '" + source + "': resolution '" + res + "' is not an integer");
    }
    return core::makeBuiltinScene(name, resolution);
}

}  // namespace volstyle::cli
