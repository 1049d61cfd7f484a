#pragma once
/// \file mesh_transfer.h
/// How the `volstyle read-mesh` child hands a parsed mesh back to the server: a plain binary file
/// (magic, counts, positions, normals, indices) that the server reads with its counts held to the
/// limits it gave the child, so nothing the child wrote is trusted beyond its size.

#include <string>

#include "core/stylize/mesh.h"

namespace volstyle::server {

/// Writes `mesh` to `path` (the child's end); IoError when it cannot.
void writeMeshTransfer(const core::Mesh& mesh, const std::string& path);

/// Reads the child's answer at `path`, its counts checked against `limits` and the file's size
/// (IoError: damaged, truncated or over the limits).
core::Mesh readMeshTransfer(const std::string& path, const core::MeshLimits& limits);

}  // namespace volstyle::server
