// The shader preprocessor runs without GL (Inviwo's shaderobject-test): includes, defines,
// #line markers and compile-log rewriting.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "core/base/errors.h"
#include "core/gl/context.h"
#include "core/gl/shader_builder.h"

using volstyle::core::gl::PreprocessedShader;
using volstyle::core::gl::ShaderBuilder;

namespace {

std::map<std::string, std::string> files = {
    {"main.comp", "#include \"common/a.glsl\"\n#include \"common/b.glsl\"\nvoid main() { f(); }\n"},
    {"common/a.glsl", "float f() { return 1.0; }\n"},
    {"common/b.glsl", "#include \"common/a.glsl\"\nfloat g() { return f(); }\n"},
    {"broken.comp", "#include \"missing.glsl\"\n"},
};

std::string loader(const std::string& name) {
    auto it = files.find(name);
    if (it == files.end()) throw volstyle::NotFound("no shader '" + name + "'");
    return it->second;
}

size_t count(const std::string& s, const std::string& needle) {
    size_t n = 0;
    for (size_t p = s.find(needle); p != std::string::npos; p = s.find(needle, p + 1)) ++n;
    return n;
}

}  // namespace

TEST(ShaderBuilder, ResolvesIncludesOnceAndInjectsDefines) {
    PreprocessedShader s = ShaderBuilder("main.comp").define("VOLSTYLE_ADJOINT", 1).preprocess(loader);
    EXPECT_EQ(s.text.rfind("#version 450 core\n", 0), 0u) << s.text;
    EXPECT_NE(s.text.find("#define VOLSTYLE_ADJOINT 1\n"), std::string::npos);
    EXPECT_EQ(count(s.text, "float f()"), 1u) << "a.glsl is included twice but must appear once";
    ASSERT_EQ(s.files.size(), 3u);
    EXPECT_EQ(s.files[0], "main.comp");
    EXPECT_EQ(s.files[1], "common/a.glsl");
    EXPECT_EQ(s.files[2], "common/b.glsl");
    // After an include, line numbering resumes in the including file.
    EXPECT_NE(s.text.find("#line 3 0\nvoid main()"), std::string::npos) << s.text;
}

TEST(ShaderBuilder, VariantKeyDependsOnDefines) {
    EXPECT_NE(ShaderBuilder("main.comp").define("A", 1).variantKey(),
              ShaderBuilder("main.comp").define("A", 2).variantKey());
    EXPECT_EQ(ShaderBuilder("main.comp").define("A", 1).define("B", 2).variantKey(),
              ShaderBuilder("main.comp").define("B", 2).define("A", 1).variantKey());
}

TEST(ShaderBuilder, AGivenLoaderIsUsedByPreprocessAndBuild) {
    // bench/sparse_sampling includes Debian's nanovdb/PNanoVDB.h through a loader of its own.
    const PreprocessedShader s = ShaderBuilder("main.comp").loader(loader).preprocess();
    EXPECT_EQ(count(s.text, "float f()"), 1u);
    EXPECT_THROW(ShaderBuilder("main.comp").preprocess(), volstyle::NotFound) << "without it, the embedded shaders only";
}

TEST(ShaderBuilder, MissingIncludeIsNotFound) {
    EXPECT_THROW(ShaderBuilder("broken.comp").preprocess(loader), volstyle::NotFound);
}

TEST(ShaderBuilder, RewritesMesaAndNvidiaLogs) {
    std::vector<std::string> names = {"render.comp", "common/march.glsl"};
    EXPECT_EQ(volstyle::core::gl::rewriteCompileLog("1:17(3): error: `x' undeclared", names),
              "common/march.glsl:17:3: error: `x' undeclared");
    EXPECT_EQ(volstyle::core::gl::rewriteCompileLog("0(42) : error C1008: undefined variable", names),
              "render.comp:42 : error C1008: undefined variable");
}

TEST(ShaderBuilder, EmbeddedShadersArePresent) {
    EXPECT_NE(volstyle::core::gl::loadShaderSource("render.comp").find("void main()"), std::string::npos);
    EXPECT_THROW(volstyle::core::gl::loadShaderSource("nope.comp"), volstyle::NotFound);
    // Every kernel preprocesses with the real embedded includes.
    for (const char* k : {"render.comp", "light_depth.comp", "occupancy.comp"})
        EXPECT_NO_THROW(ShaderBuilder(k).preprocess()) << k;
}

TEST(ShaderBuilder, ShaderDirOverrideLoadsFromDisk) {
    auto dir = std::filesystem::temp_directory_path() / "volstyle-shader-override";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "render.comp") << "// edited on disk\n";
    setenv("VOLSTYLE_SHADER_DIR", dir.c_str(), 1);
    std::string text = volstyle::core::gl::loadShaderSource("render.comp");
    EXPECT_THROW(volstyle::core::gl::loadShaderSource("occupancy.comp"), volstyle::NotFound);
    unsetenv("VOLSTYLE_SHADER_DIR");
    EXPECT_EQ(text, "// edited on disk\n");
    std::filesystem::remove_all(dir);
}

TEST(GlFeatures, MissingFeaturesAreNamed) {
    using volstyle::core::gl::missingFeatures;
    auto none = [](const char*) { return false; };
    EXPECT_TRUE(missingFeatures(45, none).empty());
    auto at43 = missingFeatures(43, none);
    ASSERT_EQ(at43.size(), 2u);  // DSA (4.5) and enhanced layouts (4.4)
    EXPECT_EQ(at43[0], "GL_ARB_direct_state_access (used for all GL object set-up)");
    // An extension stands in for the core version.
    EXPECT_EQ(missingFeatures(43, [](const char* e) { return std::string(e) == "GL_ARB_direct_state_access"; }).size(), 1u);
}
