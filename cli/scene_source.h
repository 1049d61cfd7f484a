#pragma once
/// \file scene_source.h
/// Where a volume comes from: `builtin:NAME[:RES]` or a path to an OpenVDB file.

#include <string>

#include "core/volume/volume.h"

namespace volstyle::cli {

/// Loads `builtin:cloud`, `builtin:plume:64` or `FILE.vdb`. Throws InvalidArgument / IoError.
core::Volume loadScene(const std::string& source, const core::VolumeLimits& limits = {});

}  // namespace volstyle::cli
