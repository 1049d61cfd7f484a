#include <gtest/gtest.h>

#include "core/base/errors.h"
#include "core/gl/shader_builder.h"
#include "gl_test_env.h"

using namespace volstyle;

TEST(GlContext, IsOpenGl45Core) {
    VOLSTYLE_REQUIRE_GL();
    const auto& caps = test::glContext()->capabilities();
    EXPECT_GE(caps.glVersion, 45) << caps.version;
    EXPECT_FALSE(caps.renderer.empty());
    // In CI this is Mesa llvmpipe on the surfaceless platform.
    if (caps.isSoftware) {
        EXPECT_EQ(caps.platform, "surfaceless");
    }
    std::cout << "[ renderer ] " << caps.renderer << " | " << caps.version << " | " << caps.platform
              << " | float atomics " << caps.hasFloatAtomics << "\n";
}

TEST(GlContext, CompileErrorsNameTheFileAndLine) {
    VOLSTYLE_REQUIRE_GL();
    // A define that breaks common/volume.glsl's Stencil struct is reported against that file.
    try {
        core::gl::ShaderBuilder("render.comp").define("ivec3", "undefined_type").buildCompute();
        FAIL() << "the broken variant compiled";
    } catch (const ShaderCompileError& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("render.comp;ivec3=undefined_type"), std::string::npos) << msg;
        EXPECT_NE(msg.find(".glsl:"), std::string::npos) << "log should name an included file: " << msg;
    }
}

TEST(GlContext, BadPlatformNameIsAClearError) {
    try {
        core::gl::Context::create({"vulkan", false});
        FAIL();
    } catch (const GpuError& e) {
        EXPECT_NE(std::string(e.what()).find("VOLSTYLE_EGL"), std::string::npos);
    }
}
