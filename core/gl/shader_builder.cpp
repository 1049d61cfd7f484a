#include "core/gl/shader_builder.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "core/base/errors.h"

namespace volstyle::core::gl {

// Generated at build time from core/shaders/ (cmake/EmbedShaders.cmake).
struct EmbeddedShader {
    const char* name;
    const char* text;
};
extern const EmbeddedShader kEmbeddedShaders[];
extern const size_t kEmbeddedShaderCount;

std::string loadShaderSource(const std::string& name) {
    if (const char* dir = std::getenv("VOLSTYLE_SHADER_DIR"); dir && *dir) {
        std::filesystem::path path = std::filesystem::path(dir) / name;
        std::ifstream f(path);
        if (!f) throw NotFound("no shader '" + path.string() + "' (VOLSTYLE_SHADER_DIR is set)");
        std::ostringstream s;
        s << f.rdbuf();
        return s.str();
    }
    std::string known;
    for (size_t i = 0; i < kEmbeddedShaderCount; ++i) {
        if (name == kEmbeddedShaders[i].name) return kEmbeddedShaders[i].text;
        known += (known.empty() ? "" : ", ") + std::string(kEmbeddedShaders[i].name);
    }
    throw NotFound("no embedded shader '" + name + "'; embedded: " + known);
}

namespace {

const std::regex kIncludeLine(R"(^\s*#\s*include\s+"([^"]+)\"\s*$)");

void expand(const std::string& name, const ShaderLoader& loader, std::vector<std::string>& files,
            std::set<std::string>& included, std::ostringstream& out, int depth) {
    if (depth > 32) throw ShaderCompileError("ShaderBuilder: #include nesting deeper than 32 at '" + name + "'");
    if (!included.insert(name).second) return;  // every file once (implicit include guard)
    const int index = int(files.size());
    files.push_back(name);
    std::istringstream in(loader(name));
    std::string line;
    int lineNo = 0;
    out << "#line 1 " << index << "\n";
    while (std::getline(in, line)) {
        ++lineNo;
        std::smatch m;
        if (std::regex_match(line, m, kIncludeLine)) {
            expand(m[1].str(), loader, files, included, out, depth + 1);
            out << "#line " << lineNo + 1 << " " << index << "\n";
        } else {
            out << line << "\n";
        }
    }
}

}  // namespace

PreprocessedShader ShaderBuilder::preprocess(const ShaderLoader& loader) const {
    std::ostringstream out;
    out << "#version 450 core\n";
    for (const auto& e : m_extensions) out << "#extension " << e << " : require\n";
    out << "#define VOLSTYLE_GLSL 1\n";
    for (const auto& [k, v] : m_defines) out << "#define " << k << " " << v << "\n";
    PreprocessedShader result;
    std::set<std::string> included;
    expand(m_main, loader, result.files, included, out, 0);
    result.text = out.str();
    return result;
}

std::string ShaderBuilder::variantKey() const {
    std::string key = m_main;
    for (const auto& [k, v] : m_defines) key += ";" + k + "=" + v;
    for (const auto& e : m_extensions) key += ";+" + e;
    return key;
}

std::string rewriteCompileLog(const std::string& log, const std::vector<std::string>& files) {
    // Mesa: "<file>:<line>(<col>)"; NVIDIA: "<file>(<line>)".
    static const std::regex kLocation(R"((^|\n)\s*(\d+)(?::(\d+)\((\d+)\)|\((\d+)\)))");
    std::string out;
    auto begin = std::sregex_iterator(log.begin(), log.end(), kLocation);
    size_t last = 0;
    for (auto it = begin; it != std::sregex_iterator(); ++it) {
        const std::smatch& m = *it;
        size_t fileIndex = std::stoul(m[2].str());
        if (fileIndex >= files.size()) continue;
        out += log.substr(last, size_t(m.position(0)) - last);
        out += m[1].str() + files[fileIndex] + ":" + (m[3].matched ? m[3].str() + ":" + m[4].str() : m[5].str());
        last = size_t(m.position(0) + m.length(0));
    }
    out += log.substr(last);
    return out;
}

namespace {

std::string infoLog(GLuint obj, bool isShader) {
    GLint len = 0;
    isShader ? glGetShaderiv(obj, GL_INFO_LOG_LENGTH, &len) : glGetProgramiv(obj, GL_INFO_LOG_LENGTH, &len);
    std::string log(size_t(std::max(len, 1)), '\0');
    isShader ? glGetShaderInfoLog(obj, len, nullptr, log.data()) : glGetProgramInfoLog(obj, len, nullptr, log.data());
    return std::string(log.c_str());  // drop the terminating NULs
}

/// One compiled stage; the caller deletes it once linked. Throws with the rewritten log.
GLuint compileStage(GLenum stage, const PreprocessedShader& src, const std::string& variant) {
    GLuint shader = glCreateShader(stage);
    const char* text = src.text.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        std::string log = rewriteCompileLog(infoLog(shader, true), src.files);
        glDeleteShader(shader);
        throw ShaderCompileError("compiling " + variant + " failed:\n" + log);
    }
    return shader;
}

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

bool ShaderBuilder::isRaster() const { return endsWith(m_main, ".raster"); }

Program ShaderBuilder::build() const {
    std::vector<std::pair<GLenum, PreprocessedShader>> stages;
    if (isRaster()) {
        stages.emplace_back(GL_VERTEX_SHADER, ShaderBuilder(*this).define("VOLSTYLE_VERTEX_STAGE", 1).preprocess());
        stages.emplace_back(GL_FRAGMENT_SHADER, ShaderBuilder(*this).define("VOLSTYLE_FRAGMENT_STAGE", 1).preprocess());
    } else {
        stages.emplace_back(GL_COMPUTE_SHADER, preprocess());
    }
    std::vector<GLuint> shaders;
    try {
        for (const auto& [stage, src] : stages) shaders.push_back(compileStage(stage, src, variantKey()));
    } catch (...) {
        for (GLuint s : shaders) glDeleteShader(s);
        throw;
    }
    Program program = createProgram(m_main);
    for (GLuint s : shaders) glAttachShader(program.id(), s);
    glLinkProgram(program.id());
    for (GLuint s : shaders) glDeleteShader(s);
    GLint ok = 0;
    glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
    if (!ok) {
        throw ShaderCompileError("linking " + variantKey() + " failed:\n" +
                                 rewriteCompileLog(infoLog(program.id(), false), stages.front().second.files));
    }
    return program;
}

Program ShaderBuilder::buildCompute() const {
    if (isRaster()) throw InternalError("buildCompute() on the raster shader " + m_main);
    return build();
}

}  // namespace volstyle::core::gl
