#pragma once
/// \file context.h
/// A headless OpenGL 4.5 core context through EGL: an EGL GPU device when one exists and gives
/// the context, otherwise the surfaceless platform (Mesa's llvmpipe, or a GPU driver's own, as
/// NVIDIA's). `VOLSTYLE_EGL=device|surfaceless` forces one.
/// The context is current on the thread that created it; every GL object must be created, used
/// and destroyed on that thread.

#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace volstyle::core::gl {

/// What the context can do, read once at start-up.
struct Capabilities {
    std::string platform;   ///< "device" or "surfaceless"
    std::string vendor, renderer, version;
    int glVersion = 0;      ///< e.g. 45
    bool isSoftware = false;        ///< llvmpipe / softpipe
    bool hasFloatAtomics = false;   ///< GL_NV_shader_atomic_float (image/buffer float atomicAdd)
    bool hasTimerQuery = true;      ///< core since 3.3
    int max3DTextureSize = 0;
    int maxComputeInvocations = 0;
    long long maxStorageBlockBytes = 0;  ///< GL_MAX_SHADER_STORAGE_BLOCK_SIZE (llvmpipe: 128 MiB)
    std::string memoryInfo;  ///< the extension the driver reports its memory through, or "" (gpu_memory.h)
};

struct ContextOptions {
    /// "auto", "device" or "surfaceless"; empty = read VOLSTYLE_EGL, default "auto".
    std::string platform;
    /// Create a debug context (KHR_debug messages of every severity). Also VOLSTYLE_GL_DEBUG=1.
    bool debug = false;
};

/// A GL feature volstyle needs: present when the context's version is at least `coreVersion`
/// (e.g. 45) or the driver lists `extension`.
struct RequiredFeature {
    const char* extension;
    int coreVersion;
    const char* usedFor;
};
const std::vector<RequiredFeature>& requiredFeatures();

/// The required features a context lacks, as "GL_ARB_x (used for …)". Pure: testable without GL.
std::vector<std::string> missingFeatures(int glVersion, const std::function<bool(const char*)>& hasExtension);

class Context {
public:
    /// Creates the context and makes it current. Throws GpuError with the reason (no EGL display,
    /// GL older than 4.5, a required extension missing — named in the message).
    static std::unique_ptr<Context> create(const ContextOptions& options = {});
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    const Capabilities& capabilities() const { return m_caps; }
    /// Makes this context current on the calling thread (it is released from any other).
    void makeCurrent();
    bool isOwnedByThisThread() const { return std::this_thread::get_id() == m_owner; }
    /// Blocks until the GPU has finished all submitted work.
    void finish();

private:
    Context() = default;
    /// A context on one platform ("device" or "surfaceless"); throws GpuError saying why not.
    static std::unique_ptr<Context> createOn(const std::string& platform, bool debug);
    struct Egl;
    std::unique_ptr<Egl> m_egl;
    Capabilities m_caps;
    std::thread::id m_owner;
};

}  // namespace volstyle::core::gl
