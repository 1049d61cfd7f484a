#pragma once
/// \file image.h
/// A linear-RGBA float image in memory; row 0 is the top row. Alpha is coverage (renders) or
/// per-pixel weight (painted targets).

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace volstyle::core {

struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> rgba;  ///< width*height*4, row-major, top row first

    Image() = default;
    Image(int w, int h) : width(w), height(h), rgba(size_t(w) * size_t(h) * 4, 0.0f) {}

    bool empty() const { return width == 0 || height == 0; }
    size_t pixelCount() const { return size_t(width) * size_t(height); }
    float* pixel(int x, int y) { return &rgba[(size_t(y) * width + x) * 4]; }
    const float* pixel(int x, int y) const { return &rgba[(size_t(y) * width + x) * 4]; }
    /// Number of NaN/Inf values in the image (any channel).
    size_t countNonFinite() const;
};

/// IEC 61966-2-1 sRGB transfer functions, on one channel value.
float srgbToLinear(float v);
float linearToSrgb(float v);

}  // namespace volstyle::core
