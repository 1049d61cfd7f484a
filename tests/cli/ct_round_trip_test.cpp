// A CT scan through volstyle's own files (issue #34): renders of a phantom as EXRs, solved from
// as targets (docs/FORMATS.md: a render's EXR is the picture it shows).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "../unit/test_files.h"
#include "cli_run.h"
#include "core/image/image_io.h"
#include "core/volume/vdb_io.h"
#include "core/volume/volume.h"

namespace fs = std::filesystem;
using namespace volstyle;
using test::Result;
using test::run;
using test::writeText;

namespace {

/// The modified Shepp–Logan phantom (Toft) at (x, y) ∈ [-1, 1]²: ten ellipses (value, semi-axes,
/// centre, rotation in degrees), summed.
double sheppLogan(double x, double y) {
    struct Ellipse {
        double value, a, b, x0, y0, phiDeg;
    };
    static const Ellipse kEllipses[] = {
        {1.0, 0.69, 0.92, 0, 0, 0},          {-0.8, 0.6624, 0.874, 0, -0.0184, 0}, {-0.2, 0.11, 0.31, 0.22, 0, -18},
        {-0.2, 0.16, 0.41, -0.22, 0, 18},    {0.1, 0.21, 0.25, 0, 0.35, 0},        {0.1, 0.046, 0.046, 0, 0.1, 0},
        {0.1, 0.046, 0.046, 0, -0.1, 0},     {0.1, 0.046, 0.023, -0.08, -0.605, 0}, {0.1, 0.023, 0.023, 0, -0.606, 0},
        {0.1, 0.023, 0.046, 0.06, -0.605, 0}};
    double sum = 0;
    for (const Ellipse& e : kEllipses) {
        const double phi = e.phiDeg * M_PI / 180, dx = x - e.x0, dy = y - e.y0;
        const double u = dx * std::cos(phi) + dy * std::sin(phi), v = -dx * std::sin(phi) + dy * std::cos(phi);
        if (u * u / (e.a * e.a) + v * v / (e.b * e.b) <= 1) sum += e.value;
    }
    return std::max(sum, 0.0);  // 1 − 0.8 − 0.2 rounds to −1e-16
}

/// A CT scan through our own files (issue #34): a Shepp–Logan slice (n × n × 1 voxels, extinction
/// `scale` × the phantom per world unit) rendered against a white background by `volstyle render`
/// to float EXRs from `angles` directions around it; then its extinction solved from those EXRs as
/// the targets, and again from targets composited by hand (RGB + T·background, float32, plain
/// EXRs). Returns the RMSE of each solved slice against the phantom (in the phantom's units).
std::pair<double, double> ctRoundTrip(const fs::path& dir, int n, int angles, double scale) {
    const double h = 2.0 / n;
    auto slice = [&](auto value) {
        core::Volume v({n, n, 1}, Mat4::translate({-1 + h / 2, -1 + h / 2, 0}) * Mat4::scale(Vec3d(h)));
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const float s = float(value(-1 + (i + 0.5) * h, -1 + (j + 0.5) * h));
                for (size_t c = 0; c < 3; ++c) v.extinction()[3 * v.index(i, j, 0) + c] = s;
            }
        return v;
    };
    core::saveVdb((dir / "phantom.vdb").string(), slice([&](double x, double y) { return scale * sheppLogan(x, y); }));
    core::saveVdb((dir / "start.vdb").string(), slice([&](double, double) { return 0.2 * scale; }));
    writeText(dir / "white.json", R"({"lights": [], "background": [1, 1, 1]})");
    std::string fromFiles = R"({"lighting": {"lights": [], "background": [1, 1, 1]}, "views": [)", byHand = fromFiles;
    // Cameras in the slice's plane, one row of pixels each, seeing all of it.
    const double fovY = 2 * std::atan(0.40 / (2 * n)) * 180 / M_PI;
    for (int a = 0; a < angles; ++a) {
        const double t = M_PI * a / angles;
        const std::string cam = fmt::format(R"({{"eye": [{}, {}, 0], "target": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": {}, "width": {}, "height": 1}})",
                                            4 * std::cos(t), 4 * std::sin(t), fovY, 2 * n);
        const std::string camFile = fmt::format("cam{}.json", a), exr = fmt::format("view{}.exr", a), picture = fmt::format("picture{}.exr", a);
        writeText(dir / camFile, cam);
        Result r = run("render --scene " + (dir / "phantom.vdb").string() + " --camera " + (dir / camFile).string() +
                       " --lighting " + (dir / "white.json").string() + " --exr-type float -o " + (dir / exr).string());
        EXPECT_EQ(r.status, 0) << r.out;
        // By hand, as a compositor would: RGB + T·background in float32.
        const core::LoadedImage loaded = core::loadImage((dir / exr).string());
        EXPECT_TRUE(loaded.isRender());
        core::Image composited = loaded.image;
        for (size_t i = 0; i < composited.pixelCount(); ++i) {
            for (size_t c = 0; c < 3; ++c) composited.rgba[4 * i + c] += loaded.transmittance.rgba[4 * i + c] * loaded.background.rgba[4 * i + c];
            composited.rgba[4 * i + 3] = 1;
        }
        core::SaveOptions opt;
        opt.halfFloat = false;
        core::saveImage((dir / picture).string(), composited, opt);
        fromFiles += fmt::format(R"({}{{"camera": {}, "target": "{}"}})", a ? ", " : "", cam, exr);
        byHand += fmt::format(R"({}{{"camera": {}, "target": "{}"}})", a ? ", " : "", cam, picture);
    }
    auto solve = [&](const std::string& views, const std::string& name) {
        writeText(dir / (name + ".json"), views + "]}");
        // Exact data, many views: no regularisation, and no stop for small visible changes (a CT
        // slice's transmittances change by less than 0.5/255 long before it is resolved).
        Result r = run("solve --scene " + (dir / "start.vdb").string() + " --views " + (dir / (name + ".json")).string() +
                       " --unknowns extinction --medium-radiance 0,0,0 --hull none --regularization laplacian=0 --iterations 400"
                       " --visible-change 0 --tolerance 1e-12 --quiet -o " + (dir / (name + ".vdb")).string());
        EXPECT_EQ(r.status, 0) << r.out;
        const core::Volume solved = core::loadVdb((dir / (name + ".vdb")).string());
        double sum = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double e = solved.extinction()[3 * solved.index(i, j, 0)] / scale - sheppLogan(-1 + (i + 0.5) * h, -1 + (j + 0.5) * h);
                sum += e * e;
            }
        return std::sqrt(sum / (n * n));
    };
    return {solve(fromFiles, "from_files"), solve(byHand, "by_hand")};
}

}  // namespace

TEST(Cli, ACtScanRoundTripsThroughRenderedExrs) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto [fromFiles, byHand] = ctRoundTrip(test::scratchDir(), 128, 60, 2.0);
    std::cout << "[ measured ] Shepp-Logan 128² from 60 angles: RMSE " << fromFiles << " from volstyle's EXRs, " << byHand
              << " from targets composited by hand (" << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s)\n";
    EXPECT_LE(fromFiles, 0.02);
    // The same targets (to float rounding); 400 CGLS iterations on the GPU's atomic sums end a
    // few 1e-4 apart.
    EXPECT_NEAR(fromFiles, byHand, 0.002) << "the file read as its picture is the picture";
    EXPECT_LE(byHand, 0.02);
}
