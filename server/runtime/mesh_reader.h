#pragma once
/// \file mesh_reader.h
/// Uploaded occluder meshes are parsed in a child process, never in the server (issue #35). A glTF
/// whose nodes nest 20,000 deep overflowed the stack inside assimp and ended the server; one whose
/// nodes reference each other took 10.75 GB. Now:
///  1. the server checks what the file says about itself (protocol/mesh_upload_check.h: GLB
///     lengths, glTF nesting, cycles, expanded node and vertex counts, required extensions);
///  2. `volstyle read-mesh IN --format F --out OUT` parses it with assimp under an address-space
///     limit and a time limit (the PLY header is checked against its bytes there, first), and
///     writes the flattened mesh to OUT in a plain binary layout;
///  3. the server reads OUT — positions, normals and indices, their counts checked against the
///     file's size and the limits — and validates the mesh.
/// A child that crashes, runs out of memory or time is a refused upload (422), over the limits 413.

#include <string>
#include <vector>

#include "core/stylize/mesh.h"
#include "server/runtime/vdb_reader.h"

namespace volstyle::server {

/// Reads uploaded mesh bytes of `format` ("obj", "ply", "gltf", "glb"). With an empty
/// `reader.executable` it parses in this process (tests, the CLI). Throws LimitExceeded,
/// InvalidArgument or IoError naming "the uploaded mesh".
core::Mesh loadUntrustedMesh(const std::string& bytes, const std::string& format, const core::MeshLimits& limits,
                             const VdbReaderOptions& reader);

/// The child's side is `volstyle read-mesh FILE --format F --out OUT --max-vertices N
/// --max-triangles N [--max-memory-mib M]` (cli/reader_commands.cpp; exit status as
/// child_process.h's ChildStatus).

}  // namespace volstyle::server
