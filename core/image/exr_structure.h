#pragma once
/// \file exr_structure.h
/// A walk over an OpenEXR file's headers before OpenEXR reads it (issue #9). Fuzzing found that
/// OpenEXR 3.1 (Debian 12) allocates whatever size an attribute claims before it reads the bytes:
/// a 74-byte upload made the server allocate 2 GiB and spend 7 s before "unexpected end of file".
/// This check bounds every attribute by the bytes actually present and the data window by the
/// largest image side, so a damaged or hostile header is refused at the door.

#include <cstddef>

namespace volstyle::core {

/// Throws InvalidArgument (a truncated or inconsistent header) or LimitExceeded (a data window
/// over `maxSide`) naming `nameHint`. Accepts single-part, tiled, long-name and multi-part files.
void checkExrStructure(const unsigned char* data, std::size_t size, int maxSide, const char* nameHint);

}  // namespace volstyle::core
