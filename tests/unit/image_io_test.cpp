#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/base/errors.h"
#include "core/image/clipped_pixels.h"
#include "core/image/image_io.h"
#include "core/image/jpeg_encoder.h"
#include "test_files.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

Image gradient(int w, int h) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = img.pixel(x, y);
            p[0] = float(x) / (w - 1), p[1] = float(y) / (h - 1), p[2] = 0.25f, p[3] = float(x + y) / (w + h - 2);
        }
    return img;
}

}  // namespace

TEST(Srgb, TransferFunctionsInvertEachOther) {
    // Exact inverses up to float rounding (1e-6 absolute over [0,1]).
    for (int i = 0; i <= 1000; ++i) {
        float v = float(i) / 1000;
        EXPECT_NEAR(srgbToLinear(linearToSrgb(v)), v, 1e-6f) << v;
    }
    EXPECT_NEAR(srgbToLinear(0.5f), 0.2140411f, 1e-6f);  // IEC 61966-2-1 value
}

TEST(ImageIo, Png16RoundTripLinearises) {
    auto dir = test::scratchDir();
    Image img = gradient(17, 9);
    SaveOptions opt;
    opt.bits = 16;
    opt.writeAlpha = true;
    saveImage((dir / "a.png").string(), img, opt);
    LoadedImage back = loadImage((dir / "a.png").string());
    EXPECT_TRUE(back.wasSrgb);
    EXPECT_TRUE(back.hasAlpha);
    ASSERT_EQ(back.image.width, 17);
    // 16-bit sRGB quantisation: step 1/65535 in encoded space, slope of the decode ≤ 2.4 → 5e-5.
    for (size_t i = 0; i < img.rgba.size(); ++i) EXPECT_NEAR(back.image.rgba[i], img.rgba[i], 5e-5f) << i;
}

TEST(ImageIo, Png8RoundTripWithinQuantisation) {
    auto dir = test::scratchDir();
    Image img = gradient(8, 8);
    saveImage((dir / "a.png").string(), img);
    LoadedImage back = loadImage((dir / "a.png").string());
    EXPECT_FALSE(back.hasAlpha);  // written as RGB: alpha defaults to weight 1
    for (size_t i = 0; i < img.pixelCount(); ++i) {
        for (int c = 0; c < 3; ++c) {
            // Half an 8-bit step in encoded space, times the decode slope (≤ 1 above 0.04).
            float v = img.rgba[i * 4 + c];
            EXPECT_NEAR(back.image.rgba[i * 4 + c], v, 0.5f / 255 * std::max(1.0f, 3.0f * v) + 1e-3f);
        }
        EXPECT_EQ(back.image.rgba[i * 4 + 3], 1.0f);
    }
}

TEST(ImageIo, ExrIsLinearAndExact) {
    auto dir = test::scratchDir();
    Image img = gradient(5, 4);
    img.pixel(1, 1)[0] = 37.5f;  // HDR value survives
    SaveOptions opt;
    opt.halfFloat = false;
    saveImage((dir / "a.exr").string(), img, opt);
    LoadedImage back = loadImage((dir / "a.exr").string());
    EXPECT_FALSE(back.wasSrgb);
    EXPECT_EQ(back.image.rgba, img.rgba);
}

TEST(ImageIo, ARendersExrMeansThePictureItShows) {
    // Issue #34: a volstyle render's EXR holds the medium alone (premultiplied) with its
    // background and transmittance layers; as a target it is RGB + T·background with weight 1.
    auto dir = test::scratchDir();
    Image medium = gradient(5, 4), background(5, 4), transmittance(5, 4), other(5, 4);
    for (size_t i = 0; i < medium.pixelCount(); ++i)
        for (size_t c = 0; c < 4; ++c) {
            background.rgba[4 * i + c] = 0.25f + 0.5f * float(c);
            transmittance.rgba[4 * i + c] = float(i % 5) / 5.0f + 0.01f * float(c);
            other.rgba[4 * i + c] = 9;
        }
    medium.pixel(2, 1)[3] = 0.3f;  // coverage, not a weight
    for (bool half : {true, false}) {
        saveExrLayers((dir / "render.exr").string(), {{"", &medium}, {"background", &background}, {"emission", &other}, {"transmittance", &transmittance}}, half);
        const LoadedImage loaded = loadImage((dir / "render.exr").string());
        ASSERT_TRUE(loaded.isRender());
        const Image picture = pictureOf(loaded);
        const float tolerance = half ? 2e-3f : 1e-6f;
        for (size_t i = 0; i < medium.pixelCount(); ++i) {
            for (size_t c = 0; c < 3; ++c)
                EXPECT_NEAR(picture.rgba[4 * i + c], medium.rgba[4 * i + c] + transmittance.rgba[4 * i + c] * background.rgba[4 * i + c],
                            tolerance * 4);
            EXPECT_EQ(picture.rgba[4 * i + 3], 1.0f);
        }
        EXPECT_NEAR(loaded.image.pixel(2, 1)[3], 0.3f, tolerance) << "loadImage itself keeps the file's RGBA";
    }
    // Without both layers an EXR keeps its meaning: RGB, and alpha as the weight.
    saveExrLayers((dir / "plain.exr").string(), {{"", &medium}, {"background", &background}}, false);
    const LoadedImage plain = loadImage((dir / "plain.exr").string());
    EXPECT_FALSE(plain.isRender());
    EXPECT_EQ(pictureOf(plain).rgba, medium.rgba);
}

TEST(ImageIo, ExposureScalesPngOnly) {
    auto dir = test::scratchDir();
    Image img(1, 1);
    img.pixel(0, 0)[0] = 0.1f;
    SaveOptions opt;
    opt.exposure = 1;  // ×2
    opt.bits = 16;
    saveImage((dir / "a.png").string(), img, opt);
    EXPECT_NEAR(loadImage((dir / "a.png").string()).image.rgba[0], 0.2f, 1e-4f);
}

TEST(ImageIo, CorruptPngIsIoError) {
    auto dir = test::scratchDir();
    test::writeBytes(dir / "bad.png", "\x89PNG\r\n\x1a\nthis is not a png at all");
    EXPECT_THROW(loadImage((dir / "bad.png").string()), IoError);
}

TEST(ImageIo, TruncatedPngIsIoError) {
    auto dir = test::scratchDir();
    saveImage((dir / "a.png").string(), gradient(64, 64));
    std::string bytes = test::readBytes(dir / "a.png");
    test::writeBytes(dir / "cut.png", bytes.substr(0, bytes.size() / 2));
    try {
        loadImage((dir / "cut.png").string());
        FAIL() << "a truncated PNG loaded";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("cut.png"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, NonFiniteValuesAreRejected) {
    auto dir = test::scratchDir();
    Image img = gradient(4, 4);
    img.pixel(2, 3)[1] = std::numeric_limits<float>::quiet_NaN();
    img.pixel(0, 0)[0] = std::numeric_limits<float>::infinity();
    SaveOptions opt;
    opt.halfFloat = false;
    saveImage((dir / "nan.exr").string(), img, opt);
    try {
        loadImage((dir / "nan.exr").string());
        FAIL() << "NaN image loaded";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("2 non-finite"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, MissingFileAndUnknownFormat) {
    EXPECT_THROW(loadImage("/nonexistent/x.png"), IoError);
    const std::string junk = "GIF89a not supported";
    EXPECT_THROW(loadImageFromMemory(junk.data(), junk.size(), "upload"), InvalidArgument);
    EXPECT_THROW(saveImage("/tmp/x.bmp", gradient(2, 2)), InvalidArgument);
}

TEST(ImageIo, FromMemoryMatchesFile) {
    auto dir = test::scratchDir();
    saveImage((dir / "a.png").string(), gradient(6, 6));
    std::string bytes = test::readBytes(dir / "a.png");
    LoadedImage m = loadImageFromMemory(bytes.data(), bytes.size(), "upload");
    EXPECT_EQ(m.image.rgba, loadImage((dir / "a.png").string()).image.rgba);
    EXPECT_EQ(encodeImage(gradient(6, 6), "png"), bytes);
}

// Found by scripts/fuzz.sh: 74 bytes whose "capDate" attribute claims 1.97 GB. OpenEXR 3.1
// allocated that (2 GiB, 7 s) before failing on the missing bytes; the header walk refuses it.
TEST(ImageIo, ExrAttributesLargerThanTheFileAreRefusedBeforeOpenExrReadsThem) {
    const unsigned char hostile[] = {
        0x76, 0x2f, 0x31, 0x01, 0x02, 0x00, 0x00, 0x00, 0x63, 0x61, 0x70, 0x44, 0x61, 0x74, 0x65, 0x00, 0x73, 0x74, 0x72,
        0x69, 0x6e, 0x67, 0x00, 0x13, 0x00, 0x00, 0x76, 0x2f, 0x31, 0x01, 0x02, 0x00, 0x00, 0x00, 0x63, 0x61, 0x70, 0x44,
        0x61, 0x74, 0x65, 0x00, 0x73, 0x74, 0x72, 0x69, 0x00, 0x6e, 0x67, 0x00, 0x13, 0x00, 0x00, 0x00, 0x32, 0x30, 0x32,
        0x36, 0x3a, 0x31, 0x32, 0x3a, 0x30, 0x32, 0x41, 0x30, 0x32, 0x30, 0x32, 0x36, 0x3a, 0x31, 0x34, 0x32};
    try {
        loadImageFromMemory(hostile, sizeof hostile, "upload");
        FAIL() << "expected InvalidArgument";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("'capDate' claiming 1979711507 bytes where 47 remain"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, ExrHeaderWalkAcceptsRealFilesAndChecksTheDataWindow) {
    auto dir = test::scratchDir();
    SaveOptions half;
    half.halfFloat = true;
    saveImage((dir / "a.exr").string(), gradient(8, 6), half);
    std::string bytes = test::readBytes(dir / "a.exr");
    EXPECT_EQ(loadImageFromMemory(bytes.data(), bytes.size(), "upload", 8).image.width, 8);
    EXPECT_THROW(loadImageFromMemory(bytes.data(), bytes.size(), "upload", 7), LimitExceeded);
    for (size_t cut : {size_t(4), size_t(20), size_t(60), bytes.size() / 3}) {
        EXPECT_THROW(loadImageFromMemory(bytes.data(), cut, "upload", 8), Error) << "cut at " << cut;
    }
}

TEST(ClippedPixels, AClippedPixelOfAnIntegerTargetWeighsNothing) {
    // Issue #37: paint over an 8-bit picture that was white (255, 255, 255) says "at least this
    // bright"; such pixels get weight 0, every other keeps its own.
    volstyle::core::Image wide(4, 1);
    const float values[4][4] = {{1.0f, 1.0f, 1.0f, 1.0f}, {1.0f, 0.54f, 0.24f, 1.0f}, {0.99f, 0.99f, 0.99f, 0.5f}, {1.0f, 1.0f, 1.0f, 0.0f}};
    for (int x = 0; x < 4; ++x)
        for (int c = 0; c < 4; ++c) wide.rgba[size_t(4 * x + c)] = values[x][c];
    EXPECT_EQ(volstyle::core::ignoreClippedPixels(wide), 1u) << "only the white pixel; an already weightless one is not counted";
    EXPECT_EQ(wide.rgba[3], 0.0f);
    EXPECT_EQ(wide.rgba[7], 1.0f) << "a painted colour with one channel at 255 keeps its weight";
    EXPECT_EQ(wide.rgba[11], 0.5f);
    EXPECT_EQ(wide.rgba[15], 0.0f);
}

TEST(JpegEncoder, DisplayBytesArePngsAndTheJpegShowsThemToItsStatedError) {
    // Issue #40: live frames are encoded in memory by libjpeg-turbo. Their display bytes are the
    // PNG's (linear × 2^exposure, clamped, sRGB) to ±1 level; the JPEG decodes to within its
    // quality's error on a smooth gradient with a hard edge.
    Image img(96, 64);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            float* p = &img.rgba[4 * (size_t(y) * img.width + size_t(x))];
            p[0] = float(x) / img.width * 1.2f;  // past white at the right: clamped
            p[1] = float(y) / img.height * 0.5f;
            p[2] = x > 48 ? 0.8f : 0.05f;
            p[3] = 1;
        }
    const std::string path = (std::filesystem::temp_directory_path() / "volstyle-jpeg-test.png").string();
    SaveOptions exposed;
    exposed.exposure = -0.5;
    saveImage(path, img, exposed);
    const Image png = loadImage(path).image;
    std::filesystem::remove(path);
    const std::vector<uint8_t> bytes = displayBytes(img, -0.5);
    int worst = 0;
    for (size_t i = 0; i < img.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(int(bytes[3 * i + size_t(c)]) - int(std::lround(255 * linearToSrgb(png.rgba[4 * i + size_t(c)])))));
    EXPECT_LE(worst, 1);

    for (int quality : {50, 85, 95}) {
        const std::string jpeg = encodeJpeg(img, quality);
        ASSERT_EQ(jpeg.substr(0, 2), std::string("\xff\xd8", 2));
        const Image back = loadImageFromMemory(jpeg.data(), jpeg.size(), "jpeg").image;
        ASSERT_EQ(back.width, img.width);
        const std::vector<uint8_t> shown = displayBytes(img);
        double squared = 0;
        for (size_t i = 0; i < img.pixelCount(); ++i)
            for (int c = 0; c < 3; ++c) {
                const double d = 255 * linearToSrgb(back.rgba[4 * i + size_t(c)]) - shown[3 * i + size_t(c)];
                squared += d * d;
            }
        const double psnr = 10 * std::log10(255.0 * 255.0 / (squared / double(3 * img.pixelCount())));
        std::printf("[ measured ] JPEG quality %d: %zu bytes, PSNR %.1f dB\n", quality, jpeg.size(), psnr);
        EXPECT_GE(psnr, quality >= 85 ? 42.0 : 35.0);  // measured 37.0, 44.2, 47.4 dB
    }
    EXPECT_THROW(encodeJpeg(img, 0), InvalidArgument);
    EXPECT_THROW(encodeJpeg(Image(), 85), InvalidArgument);
}
