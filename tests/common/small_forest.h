#pragma once
// builtin:forest made small for GL tests: 64×36 frames, a 512² shadow map.
#include "core/stylize/scene.h"

namespace volstyle::test {

inline core::StylizerScene smallForest() {
    core::StylizerScene s = core::builtinForest();
    s.camera.width = 64, s.camera.height = 36;
    s.light.shadowMapSize = 512;
    return s;
}

}  // namespace volstyle::test
