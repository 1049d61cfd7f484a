#include "core/gl/context.h"
#include "core/gl/gpu_memory.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>

#include "core/base/errors.h"

namespace volstyle::core::gl {

struct Context::Egl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
};

namespace {

std::string envOr(const char* name, const std::string& fallback) {
    const char* v = std::getenv(name);
    return v && *v ? std::string(v) : fallback;
}

/// The EGL device that is not Mesa's software device, the first or the VOLSTYLE_EGL_DEVICE'th
/// (0-based: a replica per GPU, docs/DEPLOY.md), if any. NVIDIA's EGL names the enumeration
/// EGL_EXT_device_base (enumeration and query together), Mesa's glvnd setup
/// EGL_EXT_device_enumeration: either will do (seen on the H200 device machine, driver 580).
EGLDeviceEXT findHardwareDevice() {
    const std::string wanted = envOr("VOLSTYLE_EGL_DEVICE", "0");
    if (wanted.empty() || wanted.size() > 2 || wanted.find_first_not_of("0123456789") != std::string::npos)
        throw GpuError("gl::Context: VOLSTYLE_EGL_DEVICE must be a GPU's index (0, 1, …), got '" + wanted + "'");
    int skip = std::stoi(wanted), found = 0;
    if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_device_enumeration") &&
        !epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_device_base"))
        return nullptr;
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    if (!eglQueryDevicesEXT(16, devices, &count)) return nullptr;
    for (EGLint i = 0; i < count; ++i) {
        const char* ext = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
        if (ext && std::strstr(ext, "EGL_MESA_device_software")) continue;
        if (skip-- == 0) return devices[i];
        ++found;
    }
    if (found > 0)
        throw GpuError("gl::Context: VOLSTYLE_EGL_DEVICE=" + wanted + " but this machine has " + std::to_string(found) + " GPU device(s)");
    return nullptr;
}

void GLAPIENTRY debugCallback(GLenum, GLenum type, GLuint id, GLenum severity, GLsizei,
                              const GLchar* message, const void*) {
    auto level = spdlog::level::debug;
    if (severity == GL_DEBUG_SEVERITY_HIGH || type == GL_DEBUG_TYPE_ERROR) level = spdlog::level::err;
    // NVIDIA reports every buffer read-back and state-based recompile as a medium performance
    // warning: on a GPU server that is thousands of log lines a solve. Debug level, like hints.
    else if (type == GL_DEBUG_TYPE_PERFORMANCE) level = spdlog::level::debug;
    else if (severity == GL_DEBUG_SEVERITY_MEDIUM) level = spdlog::level::warn;
    else if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) level = spdlog::level::trace;
    spdlog::log(level, "GL[{}]: {}", id, message);
}

}  // namespace

const std::vector<RequiredFeature>& requiredFeatures() {
    static const std::vector<RequiredFeature> features = {
        {"GL_ARB_compute_shader", 43, "every kernel"},
        {"GL_ARB_shader_storage_buffer_object", 43, "image and residual buffers"},
        {"GL_ARB_shader_image_load_store", 42, "light-depth and occupancy volumes"},
        {"GL_ARB_direct_state_access", 45, "all GL object set-up"},
        {"GL_ARB_enhanced_layouts", 44, "binding points from constants in layout.h"},
        {"GL_KHR_debug", 43, "object labels and driver messages"},
        {"GL_ARB_timer_query", 33, "GPU timings in benchmarks"},
    };
    return features;
}

std::vector<std::string> missingFeatures(int glVersion, const std::function<bool(const char*)>& hasExtension) {
    std::vector<std::string> missing;
    for (const auto& f : requiredFeatures())
        if (glVersion < f.coreVersion && !hasExtension(f.extension))
            missing.push_back(std::string(f.extension) + " (used for " + f.usedFor + ")");
    return missing;
}

namespace {

/// EGL hands every context on a platform the same display, and eglTerminate ends all of their
/// contexts at once: a second context in the process (a restarted server in tests, an engine
/// with a context of its own) lost its context when the first was destroyed. Displays are
/// counted, and terminated when their last context goes.
std::mutex g_displayMutex;
std::map<EGLDisplay, int> g_displayUsers;

bool initializeDisplay(EGLDisplay display, EGLint& major, EGLint& minor) {
    std::lock_guard lock(g_displayMutex);
    if (!eglInitialize(display, &major, &minor)) return false;
    ++g_displayUsers[display];
    return true;
}

void releaseDisplay(EGLDisplay display) {
    std::lock_guard lock(g_displayMutex);
    if (--g_displayUsers[display] > 0) return;
    g_displayUsers.erase(display);
    eglTerminate(display);
}

}  // namespace

std::unique_ptr<Context> Context::create(const ContextOptions& options) {
    const std::string platform = options.platform.empty() ? envOr("VOLSTYLE_EGL", "auto") : options.platform;
    if (platform != "auto" && platform != "device" && platform != "surfaceless")
        throw GpuError("gl::Context: VOLSTYLE_EGL must be 'device' or 'surfaceless', got '" + platform + "'");
    if (platform != "auto") return createOn(platform, options.debug);
    // auto: a GPU device if there is one, else the surfaceless platform (Mesa's, or the GPU
    // driver's own where it has one, as NVIDIA's does). A device that cannot give a GL 4.5 core
    // context falls back too, rather than leaving the server without GL.
    std::string deviceError;
    if (findHardwareDevice()) {
        try {
            return createOn("device", options.debug);
        } catch (const GpuError& e) {
            deviceError = e.what();
            spdlog::warn("gl::Context: the EGL GPU device failed ({}); trying the surfaceless platform", deviceError);
        }
    }
    try {
        return createOn("surfaceless", options.debug);
    } catch (const GpuError& e) {
        if (deviceError.empty()) throw;
        throw GpuError(std::string(e.what()) + "; before that, the EGL GPU device: " + deviceError);
    }
}

std::unique_ptr<Context> Context::createOn(const std::string& platform, bool debugOption) {
    std::unique_ptr<Context> ctx(new Context());
    ctx->m_egl = std::make_unique<Egl>();
    Egl& egl = *ctx->m_egl;
    if (platform == "device") {
        EGLDeviceEXT device = findHardwareDevice();
        if (!device) throw GpuError("gl::Context: VOLSTYLE_EGL=device but no EGL GPU device was found");
        egl.display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
        ctx->m_caps.platform = "device";
    } else {
        if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless"))
            throw GpuError("gl::Context: this EGL has no surfaceless platform (EGL_MESA_platform_surfaceless); install libegl-mesa0");
        egl.display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        ctx->m_caps.platform = "surfaceless";
    }
    EGLint major = 0, minor = 0;
    if (egl.display == EGL_NO_DISPLAY || !initializeDisplay(egl.display, major, minor)) {
        egl.display = EGL_NO_DISPLAY;  // nothing for the destructor to release
        throw GpuError("gl::Context: eglInitialize failed on the " + ctx->m_caps.platform + " platform");
    }
    if (!eglBindAPI(EGL_OPENGL_API)) throw GpuError("gl::Context: this EGL has no desktop OpenGL");

    // A configless, surfaceless GL 4.5 core context: compute work only, no default framebuffer.
    const bool debug = debugOption || envOr("VOLSTYLE_GL_DEBUG", "0") == "1";
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                 EGL_CONTEXT_MINOR_VERSION, 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_CONTEXT_OPENGL_DEBUG, debug ? EGL_TRUE : EGL_FALSE,
                                 EGL_NONE};
    egl.context = eglCreateContext(egl.display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (egl.context == EGL_NO_CONTEXT) {
        throw GpuError("gl::Context: cannot create an OpenGL 4.5 core context (EGL error 0x" +
                       fmt::format("{:x}", eglGetError()) + "); volstyle needs OpenGL 4.5");
    }
    ctx->makeCurrent();

    Capabilities& caps = ctx->m_caps;
    caps.glVersion = epoxy_gl_version();
    caps.vendor = reinterpret_cast<const char*>(glGetString(GL_VENDOR));
    caps.renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    caps.version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    caps.isSoftware = caps.renderer.find("llvmpipe") != std::string::npos ||
                      caps.renderer.find("softpipe") != std::string::npos;
    auto missing = missingFeatures(caps.glVersion, [](const char* e) { return epoxy_has_gl_extension(e); });
    if (!missing.empty()) {
        std::string list;
        for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
        throw GpuError("gl::Context: '" + caps.renderer + "' (OpenGL " + caps.version + ") lacks " + list +
                       "; volstyle needs OpenGL 4.5 core");
    }
    caps.hasFloatAtomics = epoxy_has_gl_extension("GL_NV_shader_atomic_float");
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &caps.max3DTextureSize);
    glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS, &caps.maxComputeInvocations);
    GLint64 storageBlock = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &storageBlock);
    caps.maxStorageBlockBytes = storageBlock;
    // A smaller limit, to try what a GPU with small storage blocks does (tests: sparse solves that
    // coarsen their unknowns to fit). It can only lower the driver's.
    if (const char* limit = std::getenv("VOLSTYLE_MAX_STORAGE_BLOCK_BYTES"))
        if (const long long bytes = std::atoll(limit); bytes > 0) caps.maxStorageBlockBytes = std::min(caps.maxStorageBlockBytes, bytes);
    caps.memoryInfo = gpuMemorySource();

    glEnable(GL_DEBUG_OUTPUT);
    if (debug) glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(debugCallback, nullptr);
    spdlog::debug("gl::Context: {} ({}) via EGL {} {}.{}, float atomics: {}", caps.renderer, caps.version,
                  caps.platform, major, minor, caps.hasFloatAtomics ? "yes" : "no (CAS fallback)");
    return ctx;
}

Context::~Context() {
    if (!m_egl || m_egl->display == EGL_NO_DISPLAY) return;
    eglMakeCurrent(m_egl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (m_egl->context != EGL_NO_CONTEXT) eglDestroyContext(m_egl->display, m_egl->context);
    releaseDisplay(m_egl->display);
}

void Context::makeCurrent() {
    if (!eglMakeCurrent(m_egl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_egl->context))
        throw GpuError("gl::Context: eglMakeCurrent failed");
    m_owner = std::this_thread::get_id();
}

void Context::finish() { glFinish(); }

}  // namespace volstyle::core::gl
