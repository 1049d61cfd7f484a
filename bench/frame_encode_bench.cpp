// How long a live frame takes to become bytes on the wire (issue #40): the stylizer's frame as
// JPEG in memory by libjpeg-turbo (core/image/jpeg_encoder.h, what …/stylizer/stream sends)
// against the OpenImageIO path through a temporary file (encodeImage, what the live frames used
// before) and PNG, at 960×540 and 1920×1080, on a synthetic frame with shafts-like gradients and
// foliage-like detail. Prints the median of 7 runs of each. The first column starts from display
// bytes the GPU packed (display_pack.comp: what the stream encodes now), the second from the
// float frame (the CPU converts it first).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "core/base/stopwatch.h"
#include "core/image/image_io.h"
#include "core/image/jpeg_encoder.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Image frame(int w, int h) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = &img.rgba[4 * (size_t(y) * size_t(w) + size_t(x))];
            const double shaft = 0.5 + 0.5 * std::sin(0.02 * x + 0.01 * y), leaf = ((x * 7919 + y * 104729) % 97) / 97.0;
            p[0] = float(0.6 * shaft + 0.2 * leaf), p[1] = float(0.5 * shaft + 0.25 * leaf), p[2] = float(0.3 * shaft), p[3] = 1;
        }
    return img;
}

double medianMs(const std::function<size_t()>& f, size_t& bytes) {
    std::vector<double> ms;
    for (int i = 0; i < 7; ++i) {
        const auto t0 = Clock::now();
        bytes = f();
        ms.push_back(msSince(t0));
    }
    std::sort(ms.begin(), ms.end());
    return ms[3];
}

}  // namespace

int main() {
    std::printf("| frame | JPEG q90 from GPU-packed bytes | JPEG q90 from floats, libjpeg-turbo | JPEG, OpenImageIO via a file | PNG, OpenImageIO via a file |\n"
                "|---|---|---|---|---|\n");
    for (auto [w, h] : {std::pair{960, 540}, std::pair{1920, 1080}}) {
        const Image img = frame(w, h);
        size_t packed = 0, turbo = 0, oiio = 0, png = 0;
        std::vector<uint8_t> rgbx(img.pixelCount() * 4, 255);
        const std::vector<uint8_t> rgb = displayBytes(img);
        for (size_t i = 0; i < img.pixelCount(); ++i) std::copy_n(&rgb[3 * i], 3, &rgbx[4 * i]);
        const double p = medianMs([&] { return encodeJpegRgbx(rgbx.data(), w, h, 90).size(); }, packed);
        const double a = medianMs([&] { return encodeJpeg(img, 90).size(); }, turbo);
        const double b = medianMs([&] { return encodeImage(img, "jpeg").size(); }, oiio);
        const double c = medianMs([&] { return encodeImage(img, "png").size(); }, png);
        std::printf("| %d×%d | %.1f ms, %zu KiB | %.1f ms, %zu KiB | %.1f ms, %zu KiB | %.1f ms, %zu KiB |\n", w, h, p, packed / 1024, a, turbo / 1024, b,
                    oiio / 1024, c, png / 1024);
    }
    return 0;
}
