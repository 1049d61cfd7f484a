#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <numeric>

#include "core/base/errors.h"
#include "core/gl/object.h"
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

// A write after a clear lands after it, at every size: on NVIDIA a glNamedBufferSubData into a
// buffer over 64 KiB after a glClearNamedBufferData read back zeros (gl::writeBuffer stages it).
TEST(GlContext, BufferWritesAfterAClearKeepTheirData) {
    VOLSTYLE_REQUIRE_GL();
    for (size_t count : {size_t(1000), size_t(16384), size_t(16385), size_t(200000)}) {
        std::vector<float> data(count);
        std::iota(data.begin(), data.end(), 1.0f);
        core::gl::Buffer b = core::gl::createBuffer(count * sizeof(float) + 64, nullptr, GL_DYNAMIC_STORAGE_BIT, "write-test");
        const float zero = 0;
        glClearNamedBufferData(b.id(), GL_R32F, GL_RED, GL_FLOAT, &zero);
        core::gl::writeBuffer(b, 64, count * sizeof(float), data.data());
        std::vector<float> back(count + 16);
        glGetNamedBufferSubData(b.id(), 0, GLsizeiptr(back.size() * sizeof(float)), back.data());
        for (size_t i = 0; i < 16; ++i) ASSERT_EQ(back[i], 0.0f) << "before the offset, " << count << " floats";
        for (size_t i = 0; i < count; ++i) ASSERT_EQ(back[16 + i], data[i]) << "float " << i << " of " << count;
    }
}
