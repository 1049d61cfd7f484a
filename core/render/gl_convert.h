#pragma once
/// \file gl_convert.h
/// Conversions from core's double-precision math types to the float blocks of layout.h.

#include "core/math/vec.h"
#include "core/shaders/layout.h"

namespace volstyle::core {

inline layout::Float4 f4(const Vec3d& v, double w = 0) { return {float(v.x), float(v.y), float(v.z), float(w)}; }
inline layout::Int4 i4(Int3 v, int w = 0) { return {v.x, v.y, v.z, w}; }

/// Column-major, as GLSL's mat4.
inline layout::Float4x4 toGl(const Mat4& m) {
    layout::Float4x4 r;
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) r.m[c * 4 + row] = float(m(row, c));
    return r;
}

}  // namespace volstyle::core
