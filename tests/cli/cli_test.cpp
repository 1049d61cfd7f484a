// The real `volstyle` binary: exit 0 on success, 2 with one clear line on bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../unit/test_files.h"
#include "cli_run.h"
#include "core/image/image_io.h"
#include "core/volume/builtin_scenes.h"
#include "core/volume/vdb_io.h"
#include "core/volume/volume.h"

namespace fs = std::filesystem;
using namespace volstyle;

using test::lines;
using test::run;
using test::writeText;
using test::Result;

TEST(Cli, RendersABuiltinSceneToPngAndExr) {
    auto dir = test::scratchDir();
    std::string examples = std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/";
    writeText(dir / "cam.json", R"({"eye":[0,0,3],"target":[0,0,0],"width":32,"height":24})");
    Result r = run("render --scene builtin:sphere:32 --camera " + (dir / "cam.json").string() + " --lighting " +
                   examples + "lighting.json -o " + (dir / "s.png").string());
    ASSERT_EQ(r.status, 0) << r.out;
    core::LoadedImage png = core::loadImage((dir / "s.png").string());
    EXPECT_EQ(png.image.width, 32);
    EXPECT_EQ(png.image.height, 24);
    r = run("render --scene builtin:sphere:32 --camera " + (dir / "cam.json").string() + " -o " + (dir / "s.exr").string());
    ASSERT_EQ(r.status, 0) << r.out;
    core::LoadedImage exr = core::loadImage((dir / "s.exr").string());
    EXPECT_TRUE(exr.hasAlpha);
    EXPECT_GT(exr.image.pixel(16, 12)[3], 0.5f) << "the sphere covers the centre";
}

TEST(Cli, TheReferenceRenderAgreesWithTheGlRender) {
    // `--reference`: the float64 CPU oracle with exact light integrals (issue #38 used it to tell
    // volstyle's error from Cycles'). On a smoke sphere the GL picture is within 1% of it.
    auto dir = test::scratchDir();
    writeText(dir / "cam.json", R"({"eye":[0,0.3,3],"target":[0,0,0],"width":24,"height":24})");
    const std::string common = "render --scene builtin:sphere:24 --camera " + (dir / "cam.json").string() + " --lighting " +
                               std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/lighting.json --exr-type float -o ";
    Result r = run(common + (dir / "gl.exr").string());
    ASSERT_EQ(r.status, 0) << r.out;
    r = run(common + (dir / "ref.exr").string() + " --reference");
    ASSERT_EQ(r.status, 0) << r.out;
    const core::Image gl = core::pictureOf(core::loadImage((dir / "gl.exr").string()));
    const core::LoadedImage loaded = core::loadImage((dir / "ref.exr").string());
    EXPECT_FALSE(loaded.isRender()) << "the reference writes the picture alone, not the GL path's layers";
    const core::Image& ref = loaded.image;
    double sumGl = 0, sumRef = 0;
    for (size_t i = 0; i < ref.pixelCount(); ++i)
        for (size_t c = 0; c < 3; ++c) sumGl += gl.rgba[4 * i + c], sumRef += ref.rgba[4 * i + c];
    EXPECT_GT(sumRef, 1.0);
    EXPECT_NEAR(sumGl / sumRef, 1.0, 0.01);
    EXPECT_EQ(run(common + (dir / "t.exr").string() + " --reference --mode translucent").status, 2);
}

TEST(Cli, DegenerateCameraIsExit2WithOneLine) {
    auto dir = test::scratchDir();
    writeText(dir / "cam.json", R"({"eye":[0,0,3],"target":[0,0,3],"fov_y_deg":0})");
    Result r = run("render --scene builtin:cube:16 --camera " + (dir / "cam.json").string() + " -o " + (dir / "x.png").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(lines(r.out), 1u) << r.out;
    EXPECT_NE(r.out.find("/target: must differ from eye"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("/fov_y_deg"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir / "x.png"));
}

TEST(Cli, BadInputsAreExit2) {
    auto dir = test::scratchDir();
    test::writeBytes(dir / "junk.vdb", std::string(1000, 'j'));
    writeText(dir / "bad.json", "{ not json");
    const std::string out = " -o " + (dir / "x.png").string();
    struct Case {
        std::string args, expect;
    } cases[] = {
        {"render --scene " + (dir / "junk.vdb").string() + out, "is not an OpenVDB file"},
        {"render --scene builtin:smoke" + out, "unknown scene 'smoke'"},
        {"render --scene builtin:cube:16 --camera " + (dir / "missing.json").string() + out, "no such file"},
        {"render --scene builtin:cube:16 -o " + (dir / "absent" / "x.png").string(), "no such folder"},
        {"render --scene " + (dir / "absent.vdb").string() + out, "no such file"},
        {"render --scene builtin:cube:16 --camera " + (dir / "bad.json").string() + out, "not valid JSON"},
        {"render --scene builtin:cube:16 --step 0" + out, "step"},
        {"render --scene builtin:cube:16 --zoom 2" + out, "unknown option '--zoom'"},
        {"render --scene builtin:cube:16 -o " + (dir / "x.bmp").string(), ".png or .exr"},
        {"info " + (dir / "junk.vdb").string(), "is not an OpenVDB file"},
        {"frobnicate", "unknown command"},
    };
    for (const auto& c : cases) {
        Result r = run(c.args);
        EXPECT_EQ(r.status, 2) << c.args << "\n" << r.out;
        EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << "\n" << r.out;
        EXPECT_EQ(r.out.find("()"), std::string::npos) << "no function names in messages: " << r.out;
    }
    EXPECT_FALSE(fs::exists(dir / "absent")) << "-o into a missing folder must not create it";
}

TEST(Cli, VersionAndHelpDescribeEveryOptionWithItsDefault) {
    Result version = run("--version");
    EXPECT_EQ(version.status, 0);
    EXPECT_NE(version.out.find("volstyle 0."), std::string::npos) << version.out;
    Result overview = run("help");
    EXPECT_EQ(overview.status, 0);
    for (const char* command : {"serve", "render", "solve", "stylize", "animate", "info", "convert"})
        EXPECT_NE(overview.out.find(std::string("  ") + command), std::string::npos) << command << "\n" << overview.out;
    for (const char* command : {"serve", "render", "solve", "stylize", "animate"}) {
        Result help = run(std::string("help ") + command);
        EXPECT_EQ(help.status, 0) << command;
        EXPECT_EQ(help.out, run(std::string(command) + " --help").out) << command;
        // Every option line says what it does, and every option that takes a value its default
        // (or that it is required).
        size_t options = 0;
        std::istringstream lines(help.out.substr(help.out.find("options:")));
        for (std::string line; std::getline(lines, line);) {
            if (line.rfind("  --", 0) != 0 || line.rfind("  --help", 0) == 0) continue;
            ++options;
            std::istringstream words(line);
            std::string flag, second;
            words >> flag >> second;
            const bool takesValue = !second.empty() && second.find_first_of("abcdefghijklmnopqrstuvwxyz") == std::string::npos;
            EXPECT_GT(line.size(), 40u) << command << ": " << line;
            if (takesValue) {
                EXPECT_TRUE(line.find("default") != std::string::npos || line.find("required") != std::string::npos)
                    << command << ": " << line;
            }
        }
        EXPECT_GE(options, 3u) << help.out;
    }
}

TEST(Cli, InfoDescribesAVdb) {
    auto dir = test::scratchDir();
    core::saveVdb((dir / "cube.vdb").string(), core::makeBuiltinScene("cube", 16));
    Result r = run("info " + (dir / "cube.vdb").string());
    ASSERT_EQ(r.status, 0) << r.out;
    EXPECT_NE(r.out.find("density"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("dims 16x16x16"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("values [2, 2]"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("loads as a 16x16x16 volume"), std::string::npos) << r.out;
    // And the file renders.
    EXPECT_EQ(run("render --scene " + (dir / "cube.vdb").string() + " -o " + (dir / "c.png").string()).status, 0);
}

TEST(Cli, SolvesTheReadmeExample) {
    auto dir = test::scratchDir();
    const std::string example = std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/solve/views.json";
    Result r = run("solve --scene builtin:cloud:64 --views " + example + " --unknowns emission --iterations 12 -o " +
                   (dir / "glow.vdb").string());
    ASSERT_EQ(r.status, 0) << r.out;
    EXPECT_NE(r.out.find("12/12"), std::string::npos) << "progress on stderr: " << r.out;
    core::Volume v = core::loadVdb((dir / "glow.vdb").string());
    ASSERT_TRUE(v.hasEmission());
    float peak = 0;
    for (float e : v.emission()) peak = std::max(peak, e);
    EXPECT_GT(peak, 0.05f) << "the painted glow became emission";
    // The report line: RMS falls by more than 5x in 12 iterations; then what is out of reach.
    auto at = r.out.find("RMS ", r.out.find("emission: "));
    ASSERT_NE(at, std::string::npos) << r.out;
    double before = 0, after = 0;
    ASSERT_EQ(std::sscanf(r.out.c_str() + at, "RMS %lf -> %lf", &before, &after), 2) << r.out;
    EXPECT_LT(after, before / 5) << r.out;
    EXPECT_NE(r.out.find("view 1: RMS"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("is out of reach of emission"), std::string::npos) << r.out;
}

TEST(Cli, SolveBadInputsAreExit2) {
    auto dir = test::scratchDir();
    const std::string example = std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/solve/views.json";
    writeText(dir / "views.json", R"({"views": [{"camera": {"eye": [0,0,3], "target": [0,0,0]}, "target": "missing.png"}]})");
    writeText(dir / "opts.json", R"({"unknowns": ["extinction"], "basis": "cubic"})");
    const std::string out = " -o " + (dir / "x.vdb").string();
    struct Case {
        std::string args, expect;
    } cases[] = {
        {"solve --scene builtin:cloud:32 --views " + (dir / "views.json").string() + out, "missing.png"},
        {"solve --scene builtin:cloud:32 --views " + example + " --unknowns colour" + out, "--unknowns must be"},
        {"solve --scene builtin:cloud:32 --views " + example + " --options " + (dir / "opts.json").string() + out, "/basis"},
        {"solve --scene builtin:cloud:32 --views " + example + " --unknowns extinction" + out, "e.g. the background's: --medium-radiance 0.32,0.5,0.82"},
        {"solve --scene builtin:cloud:32 --views " + example + " --regularization smooth=1" + out, "unknown term 'smooth'"},
        {"solve --scene builtin:cloud:32 --views " + example + " -o x.png", "must end in .vdb"},
    };
    for (const auto& c : cases) {
        Result r = run(c.args);
        EXPECT_EQ(r.status, 2) << c.args << "\n" << r.out;
        EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << "\n" << r.out;
        EXPECT_EQ(r.out.find("()"), std::string::npos) << "no function names in messages: " << r.out;
    }
}

TEST(Cli, StylizesASceneFileAndItsAovs) {
    auto dir = test::scratchDir();
    const std::string example = std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/stylize/window.json";
    writeText(dir / "cam.json", R"({"eye":[-3.5,1.4,-8.5],"target":[0.2,1.6,-1.5],"width":48,"height":32,"far":30})");
    const std::string camera = " --camera " + (dir / "cam.json").string();
    Result r = run("stylize --scene " + example + camera + " --steps 64 -o " + (dir / "frame.exr").string());
    ASSERT_EQ(r.status, 0) << r.out;
    r = run("stylize --scene " + example + camera + " --steps 64 --aov average_visibility -o " + (dir / "vbar.exr").string());
    ASSERT_EQ(r.status, 0) << r.out;
    const core::Image frame = core::loadImage((dir / "frame.exr").string()).image;
    const core::Image vbar = core::loadImage((dir / "vbar.exr").string()).image;
    ASSERT_EQ(vbar.width, 48);
    float lo = 1, hi = 0;
    for (size_t i = 0; i < vbar.pixelCount(); ++i) lo = std::min(lo, vbar.rgba[4 * i]), hi = std::max(hi, vbar.rgba[4 * i]);
    EXPECT_LT(lo, 0.05f) << "rays that stay in the dark room";
    EXPECT_GT(hi, 0.1f) << "rays through the window's shaft";
    EXPECT_EQ(frame.width, 48);
}

TEST(Cli, StylizesACameraPathAsASequenceAndAVideo) {
    // docs/examples/stylize/path.json: two key frames 2 s apart; 2 fps gives 5 frames.
    auto dir = test::scratchDir();
    const std::string example = std::string(VOLSTYLE_SOURCE_DIR) + "/docs/examples/stylize/path.json";
    const bool video = std::system("command -v ffmpeg > /dev/null 2>&1") == 0;
    Result r = run("stylize --scene " + example + " --sequence " + (dir / "frames").string() + " --fps 2" +
                   (video ? " --video " + (dir / "path.mp4").string() : std::string()));
    ASSERT_EQ(r.status, 0) << r.out;
    for (int i = 0; i < 5; ++i) {
        const auto frame = dir / "frames" / ("frame_0000" + std::to_string(i) + ".png");
        ASSERT_TRUE(std::filesystem::exists(frame)) << frame;
        EXPECT_EQ(core::loadImage(frame.string()).image.width, 320);
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "frames" / "frame_00005.png"));
    if (video) {
        EXPECT_GT(std::filesystem::file_size(dir / "path.mp4"), 1000u);
    }
}

TEST(Cli, StylizeBadInputsAreExit2WithTheProblem) {
    auto dir = test::scratchDir();
    const std::string out = " -o " + (dir / "x.png").string();
    writeText(dir / "bad.json", R"({"occluders":[{"mesh":"missing.obj"}],"medium":{"albedo":2},"light":{"type":"sun"},"colour":1})");
    writeText(dir / "nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    writeText(dir / "nan.json", R"({"occluders":[{"mesh":"nan.obj"}]})");
    writeText(dir / "missing.json", R"({"occluders":[{"mesh":"missing.obj"}]})");
    const std::pair<std::string, std::string> cases[] = {
        {"stylize --scene builtin:nothing" + out, "unknown scene"},
        {"stylize --scene " + (dir / "bad.json").string() + out, "/medium/albedo"},
        {"stylize --scene " + (dir / "bad.json").string() + out, "/light/type"},
        {"stylize --scene " + (dir / "bad.json").string() + out, "/colour"},
        {"stylize --scene " + (dir / "nan.json").string() + out, "/occluders/0/mesh"},
        {"stylize --scene " + (dir / "nan.json").string() + out, "non-finite"},
        {"stylize --scene " + (dir / "missing.json").string() + out, "no such file"},
        {"stylize --scene builtin:forest --steps 0" + out, "/steps"},
        {"stylize --scene builtin:forest --aov colour" + out, "--aov"},
        {"stylize --scene builtin:forest --method fast" + out, "--method"},
        {"stylize --scene builtin:forest --time nan" + out, "--time"},
        {"stylize --scene builtin:forest --fps 4" + out, "--fps belongs to --sequence"},
        {"stylize --scene builtin:forest --sequence " + (dir / "seq").string(), "--end is required"},
        {"stylize --scene builtin:forest --sequence " + (dir / "seq").string() + " --end 1 --fps 500", "fps"},
        {"stylize --scene builtin:forest --sequence " + (dir / "seq").string() + " --end 1 --video x.avi", "--video must end in .mp4"},
    };
    for (const auto& [args, expected] : cases) {
        Result r = run(args);
        EXPECT_EQ(r.status, 2) << args << "\n" << r.out;
        EXPECT_EQ(lines(r.out), 1u) << args << "\n" << r.out;
        EXPECT_NE(r.out.find(expected), std::string::npos) << args << "\n" << r.out;
    }
}

TEST(Cli, SolvesTheEnvironmentLightingAndWritesItBack) {
    // Targets rendered under 8 lobes through the CLI; solved from black; the written lighting
    // renders the same image again.
    auto dir = test::scratchDir();
    std::string radiance;
    for (int i = 0; i < 8; ++i) radiance += std::string(i ? "," : "") + "[" + std::to_string(0.2 + 0.1 * i) + ",0.5," + std::to_string(1.0 - 0.1 * i) + "]";
    writeText(dir / "truth.json", R"({"background": [0, 0, 0], "environment": {"lobes": 8, "light_volume_resolution": 16, "radiance": [)" + radiance + "]}}");
    const std::string cam = R"({"eye": [0, 0.3, 3.2], "target": [0, 0, 0], "fov_y_deg": 40, "width": 32, "height": 32})";
    writeText(dir / "cam.json", cam);
    Result r = run("render --scene builtin:cloud:16 --camera " + (dir / "cam.json").string() + " --lighting " + (dir / "truth.json").string() +
                   " -o " + (dir / "t.exr").string());
    ASSERT_EQ(r.status, 0) << r.out;
    writeText(dir / "views.json", R"({"views": [{"camera": )" + cam + R"(, "target": "t.exr"}], "lighting": {"background": [0, 0, 0]}})");
    r = run("solve --scene builtin:cloud:16 --views " + (dir / "views.json").string() + " --unknowns lights --lights 8 --quiet -o " +
            (dir / "sky.json").string());
    ASSERT_EQ(r.status, 0) << r.out;
    EXPECT_NE(r.out.find("lights: 8 lobes"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(dir / "sky.exr"));
    const core::Image sky = core::loadImage((dir / "sky.exr").string()).image;
    EXPECT_EQ(sky.width, 2 * sky.height);
    r = run("render --scene builtin:cloud:16 --camera " + (dir / "cam.json").string() + " --lighting " + (dir / "sky.json").string() +
            " -o " + (dir / "again.exr").string());
    ASSERT_EQ(r.status, 0) << r.out;
    const core::Image want = core::loadImage((dir / "t.exr").string()).image, got = core::loadImage((dir / "again.exr").string()).image;
    double err = 0, norm = 0;
    for (size_t i = 0; i < want.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) err += std::pow(got.rgba[4 * i + c] - want.rgba[4 * i + c], 2), norm += std::pow(want.rgba[4 * i + c], 2);
    EXPECT_LT(std::sqrt(err / norm), 0.02);  // one view, 8 lobes: the image is matched, if not every lobe

    // Bad input: exit 2, one line naming the problem.
    for (const auto& [args, expect] : std::vector<std::pair<std::string, std::string>>{
             {" --unknowns lights --lights 300 -o " + (dir / "s.json").string(), "--lights"},
             {" --unknowns lights -o " + (dir / "s.vdb").string(), "must end in .json"},
             {" --lights 4 -o " + (dir / "s.vdb").string(), "need --unknowns lights"}}) {
        r = run("solve --scene builtin:cloud:16 --views " + (dir / "views.json").string() + args);
        EXPECT_EQ(r.status, 2) << args << "\n" << r.out;
        EXPECT_NE(r.out.find(expect), std::string::npos) << args << "\n" << r.out;
    }
}
