#pragma once
/// \file vec.h
/// Small value types for host-side math: Vec3 (float or double), Int3, and an affine Mat4.
/// Column vectors; `Mat4` composes right-to-left, names read `worldFromIndex * p`.

#include <array>
#include <cmath>
#include <cstdint>
#include <ostream>

namespace volstyle {

template <typename T>
struct Vec3T {
    T x = 0, y = 0, z = 0;
    constexpr Vec3T() = default;
    constexpr Vec3T(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
    constexpr explicit Vec3T(T v) : x(v), y(v), z(v) {}
    template <typename U>
    constexpr explicit Vec3T(const Vec3T<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}

    constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr Vec3T operator+(const Vec3T& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3T operator-(const Vec3T& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3T operator*(const Vec3T& o) const { return {x * o.x, y * o.y, z * o.z}; }
    constexpr Vec3T operator/(const Vec3T& o) const { return {x / o.x, y / o.y, z / o.z}; }
    constexpr Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3T operator-() const { return {-x, -y, -z}; }
    constexpr Vec3T& operator+=(const Vec3T& o) { return *this = *this + o; }
    constexpr Vec3T& operator*=(T s) { return *this = *this * s; }
    constexpr bool operator==(const Vec3T&) const = default;
};

template <typename T>
constexpr Vec3T<T> operator*(T s, const Vec3T<T>& v) { return v * s; }
template <typename T>
constexpr T dot(const Vec3T<T>& a, const Vec3T<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T>
constexpr Vec3T<T> cross(const Vec3T<T>& a, const Vec3T<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
T length(const Vec3T<T>& v) { return std::sqrt(dot(v, v)); }
template <typename T>
Vec3T<T> normalize(const Vec3T<T>& v) { return v / length(v); }
template <typename T>
constexpr T maxComponent(const Vec3T<T>& v) { return v.x > v.y ? (v.x > v.z ? v.x : v.z) : (v.y > v.z ? v.y : v.z); }
template <typename T>
constexpr T minComponent(const Vec3T<T>& v) { return v.x < v.y ? (v.x < v.z ? v.x : v.z) : (v.y < v.z ? v.y : v.z); }
template <typename T>
std::ostream& operator<<(std::ostream& os, const Vec3T<T>& v) {
    return os << "[" << v.x << ", " << v.y << ", " << v.z << "]";
}

using Vec3 = Vec3T<float>;
using Vec3d = Vec3T<double>;

/// Integer grid dimensions or voxel coordinates.
struct Int3 {
    int x = 0, y = 0, z = 0;
    constexpr int operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr int64_t volume() const { return int64_t(x) * y * z; }
    constexpr bool operator==(const Int3&) const = default;
};
inline std::ostream& operator<<(std::ostream& os, const Int3& v) {
    return os << v.x << "x" << v.y << "x" << v.z;
}

/// Row-major 4x4 matrix of doubles, used for affine transforms applied to column vectors.
struct Mat4 {
    std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

    double& operator()(int r, int c) { return m[r * 4 + c]; }
    double operator()(int r, int c) const { return m[r * 4 + c]; }

    static Mat4 identity() { return {}; }
    bool operator==(const Mat4&) const = default;  ///< exact: a transform read back bit for bit
    static Mat4 translate(const Vec3d& t) {
        Mat4 r;
        r(0, 3) = t.x, r(1, 3) = t.y, r(2, 3) = t.z;
        return r;
    }
    static Mat4 scale(const Vec3d& s) {
        Mat4 r;
        r(0, 0) = s.x, r(1, 1) = s.y, r(2, 2) = s.z;
        return r;
    }
    Mat4 operator*(const Mat4& o) const {
        Mat4 r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                double s = 0;
                for (int k = 0; k < 4; ++k) s += (*this)(i, k) * o(k, j);
                r(i, j) = s;
            }
        return r;
    }
    Vec3d applyPoint(const Vec3d& p) const {
        return {(*this)(0, 0) * p.x + (*this)(0, 1) * p.y + (*this)(0, 2) * p.z + (*this)(0, 3),
                (*this)(1, 0) * p.x + (*this)(1, 1) * p.y + (*this)(1, 2) * p.z + (*this)(1, 3),
                (*this)(2, 0) * p.x + (*this)(2, 1) * p.y + (*this)(2, 2) * p.z + (*this)(2, 3)};
    }
    Vec3d applyVector(const Vec3d& v) const {
        return {(*this)(0, 0) * v.x + (*this)(0, 1) * v.y + (*this)(0, 2) * v.z,
                (*this)(1, 0) * v.x + (*this)(1, 1) * v.y + (*this)(1, 2) * v.z,
                (*this)(2, 0) * v.x + (*this)(2, 1) * v.y + (*this)(2, 2) * v.z};
    }
    /// Inverse of an affine matrix (last row 0 0 0 1). Throws InvalidArgument if singular.
    Mat4 inverseAffine() const;
    bool isAffine() const {
        return m[12] == 0 && m[13] == 0 && m[14] == 0 && m[15] == 1;
    }
};

}  // namespace volstyle
