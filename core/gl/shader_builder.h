#pragma once
/// \file shader_builder.h
/// Shader variants from the files under core/shaders/ (STYLE §3.5): compute programs from `.comp`
/// files, and rasterization programs from `.raster` files, one source compiled as the vertex stage
/// (VOLSTYLE_VERTEX_STAGE) and as the fragment stage (VOLSTYLE_FRAGMENT_STAGE). Resolves
/// `#include "file"` (each file once), prepends `#version 450`, extensions and `#define`s, and
/// marks every file with `#line N <file-index>` so compile logs can be rewritten to `file:line`.
/// Preprocessing needs no GL context (tested without one); build() compiles on the GL thread.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/gl/object.h"

namespace volstyle::core::gl {

/// Returns the text of a shader file by its name relative to core/shaders/ (throws NotFound).
using ShaderLoader = std::function<std::string(const std::string& name)>;

/// The embedded copy of a shader, or — when VOLSTYLE_SHADER_DIR is set — the file on disk there,
/// for edit-and-rerun without rebuilding.
std::string loadShaderSource(const std::string& name);

struct PreprocessedShader {
    std::string text;
    std::vector<std::string> files;  ///< index used in `#line N index` → file name
};

/// Rewrites driver compile logs (Mesa "2:17(3): error", NVIDIA "2(17) : error") to name files.
std::string rewriteCompileLog(const std::string& log, const std::vector<std::string>& files);

class ShaderBuilder {
public:
    explicit ShaderBuilder(std::string mainFile) : m_main(std::move(mainFile)) {}
    ShaderBuilder& define(const std::string& name, long long value) {
        m_defines[name] = std::to_string(value);
        return *this;
    }
    ShaderBuilder& define(const std::string& name, const std::string& value) {
        m_defines[name] = value;
        return *this;
    }
    /// `#extension name : require`, emitted right after `#version`.
    ShaderBuilder& extension(const std::string& name) {
        m_extensions.push_back(name);
        return *this;
    }

    /// Where `#include`d and main files come from (default: the embedded shaders). A benchmark
    /// or a tool can add files from elsewhere (e.g. Debian's nanovdb/PNanoVDB.h).
    ShaderBuilder& loader(ShaderLoader loader) {
        m_loader = std::move(loader);
        return *this;
    }

    /// Preprocesses with `loader`, or with the builder's own (default: loadShaderSource).
    PreprocessedShader preprocess(const ShaderLoader& loader) const;
    PreprocessedShader preprocess() const { return preprocess(m_loader ? m_loader : ShaderLoader(loadShaderSource)); }
    /// A key naming this variant (file + defines + extensions), for program caches.
    std::string variantKey() const;
    const std::string& mainFile() const { return m_main; }

    /// Compiles and links the program (compute, or vertex + fragment for a `.raster` file).
    /// Throws ShaderCompileError whose message holds the rewritten log and the variant's defines.
    Program build() const;
    /// build() for a compute shader (InternalError for a raster one).
    Program buildCompute() const;
    bool isRaster() const;

private:
    std::string m_main;
    std::map<std::string, std::string> m_defines;
    std::vector<std::string> m_extensions;
    ShaderLoader m_loader;
};

}  // namespace volstyle::core::gl
