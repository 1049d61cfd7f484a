#include "core/base/errors.h"
#include "core/math/vec.h"

namespace volstyle {

Mat4 Mat4::inverseAffine() const {
    // Invert the 3x3 linear part by cofactors, then the translation: x = A^-1 (y - t).
    const Mat4& a = *this;
    double c00 = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
    double c01 = a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2);
    double c02 = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
    double det = a(0, 0) * c00 + a(0, 1) * c01 + a(0, 2) * c02;
    double scale = std::abs(a(0, 0)) + std::abs(a(1, 1)) + std::abs(a(2, 2));
    if (!(std::abs(det) > 1e-300) || !std::isfinite(det) || std::abs(det) < 1e-12 * scale * scale * scale)
        throw InvalidArgument("the transform is singular (determinant " +
                              std::to_string(det) + ")");
    Mat4 r;
    double inv = 1.0 / det;
    r(0, 0) = c00 * inv;
    r(0, 1) = (a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2)) * inv;
    r(0, 2) = (a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1)) * inv;
    r(1, 0) = c01 * inv;
    r(1, 1) = (a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0)) * inv;
    r(1, 2) = (a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2)) * inv;
    r(2, 0) = c02 * inv;
    r(2, 1) = (a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1)) * inv;
    r(2, 2) = (a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0)) * inv;
    Vec3d t = r.applyVector({a(0, 3), a(1, 3), a(2, 3)});
    r(0, 3) = -t.x, r(1, 3) = -t.y, r(2, 3) = -t.z;
    return r;
}

}  // namespace volstyle
