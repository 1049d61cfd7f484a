#pragma once
/// \file build_version.h
/// The version of this build (the project's version in CMakeLists.txt): what `volstyle --version`
/// prints and GET /health reports.

namespace volstyle::protocol {

const char* versionString();

}  // namespace volstyle::protocol
