#include "core/stylize/stylizer_passes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/base/errors.h"
#include "core/render/gl_convert.h"
#include "core/stylize/morphology_gpu.h"

namespace volstyle::core::stylize {
namespace {

gl::Texture texture2D(GLenum format, int w, int h, const char* label) { return gl::createTexture2D(format, w, h, GL_NEAREST, label); }

/// The levels of the min-max mipmap of an n×n map, down to 1×1: each one's side and first entry
/// (level 0 is the map itself, at entry 0); `entries` counts them all.
struct MinMaxLevels {
    std::vector<int> sides, offsets;
    size_t entries = 0;
};

MinMaxLevels minMaxLevels(int n) {
    MinMaxLevels l{{n}, {0}, size_t(n) * n};
    while (l.sides.back() > 1) {
        const int side = (l.sides.back() + 1) / 2;
        l.offsets.push_back(int(l.entries));
        l.sides.push_back(side);
        l.entries += size_t(side) * side;
    }
    return l;
}

/// A framebuffer drawing into `colours` (in order: attachment 0, 1, …; none: depth only) and `depth`.
gl::Framebuffer framebuffer(const char* label, const gl::Texture& depth, std::initializer_list<const gl::Texture*> colours, const char* what) {
    gl::Framebuffer fb = gl::createFramebuffer(label);
    glNamedFramebufferTexture(fb.id(), GL_DEPTH_ATTACHMENT, depth.id(), 0);
    std::vector<GLenum> buffers;
    for (const gl::Texture* c : colours) {
        buffers.push_back(GLenum(GL_COLOR_ATTACHMENT0 + buffers.size()));
        glNamedFramebufferTexture(fb.id(), buffers.back(), c->id(), 0);
    }
    if (buffers.empty()) glNamedFramebufferDrawBuffer(fb.id(), GL_NONE);
    else glNamedFramebufferDrawBuffers(fb.id(), GLsizei(buffers.size()), buffers.data());
    gl::checkFramebufferComplete(fb, what);
    return fb;
}

/// A mesh's GPU copy in the device's cache, with the mesh it was made from (a key names the
/// mesh's address, which a new mesh may reuse once the old one is gone).
struct CachedMesh {
    std::weak_ptr<const Mesh> mesh;
    std::shared_ptr<const GpuMesh> gpu;
};

Image readChannelPlane(const std::vector<float>& plane, int w, int h, int channel, bool broadcast) {
    Image img(w, h);
    for (size_t i = 0; i < img.pixelCount(); ++i) {
        const float* src = &plane[4 * i];
        for (int c = 0; c < 3; ++c) img.rgba[4 * i + c] = broadcast ? src[channel] : src[c];
        img.rgba[4 * i + 3] = 1;
    }
    return img;
}

/// Draws the occluders `which(i)` accepts with `builder` from `clipFromWorld` (into the bound framebuffer).
void drawOccluders(Frame& f, const gl::ShaderBuilder& builder, const Mat4& clipFromWorld, const std::function<bool(size_t)>& which) {
    glUseProgram(f.device.program(builder).id());
    f.p.clipFromWorld = toGl(clipFromWorld);
    for (size_t i = 0; i < f.meshes.size(); ++i) {
        if (!which(i)) continue;
        f.p.worldFromObject = toGl(f.scene.occluders[i].worldFromObject);
        f.p.surface = f4(f.scene.occluders[i].colour, double(i + 1));
        f.device.setParams(f.p);
        glBindVertexArray(f.meshes[i]->vao.id());
        glDrawElements(GL_TRIANGLES, f.meshes[i]->indexCount, GL_UNSIGNED_INT, nullptr);
    }
    glBindVertexArray(0);
}

/// Clears a shadow framebuffer (depth 1; ids 0 when it has them) and draws the occluders `which` accepts.
void renderShadow(Frame& f, const gl::Framebuffer& fb, bool ids, const std::function<bool(size_t)>& which) {
    const float zero[4] = {0, 0, 0, 0}, one = 1;
    if (ids) glClearNamedFramebufferfv(fb.id(), GL_COLOR, 0, zero);
    glClearNamedFramebufferfv(fb.id(), GL_DEPTH, 0, &one);
    glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
    glViewport(0, 0, f.targets.n, f.targets.n);
    if (!f.meshes.empty()) drawOccluders(f, gl::ShaderBuilder("occluders.raster").define("VOLSTYLE_PASS_SHADOW", 1), f.map.clip, which);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

/// A depth map into a buffer, on the GPU (no round trip).
void copyToBuffer(const StylizerTargets& t, const gl::Texture& depthMap, const gl::Buffer& into) {
    glBindBuffer(GL_PIXEL_PACK_BUFFER, into.id());
    glGetTextureImage(depthMap.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(t.mapBytes), nullptr);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
}

/// One manipulated occluder's shadow edits on its map in `t.part` (Sec. 4): closing, epipolar
/// dilation and erosion, holes.
void editOne(Frame& f, size_t i, float holeThreshold) {
    const StylizerTargets& t = f.targets;
    const Manipulation& m = f.scene.occluders[i].manipulation;
    const int n = t.n;
    closeDepthBuffer(f.device, t.part, n, m.closingRadius, m.closingShape);
    const auto& [objectLo, objectHi] = f.map.objectBounds[i];
    if (m.dilationLength > 0) {
        dilateEpipolarBuffer(f.device, t.part, n, epipoleOf(f.map.clip, f.scene.camera.eye, n), dilationTexels(f.map, f.scene, i));
        erodeBoxBuffer(f.device, t.part, n, m.erosionPx);
    }
    if (m.holeProbability > 0) {
        HoleMap h = holeMapOf(f.map.clip, f.map.spot, f.map.spotTan * length((objectLo + objectHi) * 0.5 - f.scene.light.position), n,
                              m.holeFrequency);
        h.threshold = holeThreshold;
        holeTimeOffset(f.scene.time, m.holeSpeed, h.offsetX, h.offsetY);
        h.octaves = m.holeOctaves;
        h.persistence = m.holePersistence;
        h.seed = m.holeSeed;
        cutHolesBuffer(f.device, t.part, n, h);
    }
}

}  // namespace

GpuMesh::GpuMesh(const Mesh& m) {
    std::vector<float> interleaved;
    interleaved.reserve(m.positions.size() * 6);
    for (size_t i = 0; i < m.positions.size(); ++i)
        for (const Vec3& v : {m.positions[i], m.normals[i]}) interleaved.insert(interleaved.end(), {v.x, v.y, v.z});
    vertices = gl::createBuffer(interleaved.size() * sizeof(float), interleaved.data(), 0, "occluder-vertices");
    indices = gl::createBuffer(m.indices.size() * sizeof(uint32_t), m.indices.data(), 0, "occluder-indices");
    indexCount = GLsizei(m.indices.size());
    vao = gl::createVertexArray("occluder");
    glVertexArrayVertexBuffer(vao.id(), 0, vertices.id(), 0, 6 * sizeof(float));
    for (GLuint attr : {0u, 1u}) {
        glEnableVertexArrayAttrib(vao.id(), attr);
        glVertexArrayAttribFormat(vao.id(), attr, 3, GL_FLOAT, GL_FALSE, attr * 3 * sizeof(float));
        glVertexArrayAttribBinding(vao.id(), attr, 0);
    }
    glVertexArrayElementBuffer(vao.id(), indices.id());
}

std::shared_ptr<const GpuMesh> gpuMesh(GpuDevice& device, const std::shared_ptr<const Mesh>& mesh) {
    const std::string key = "stylizer-mesh/" + std::to_string(reinterpret_cast<uintptr_t>(mesh.get()));
    if (auto cached = device.cache().find<CachedMesh>(key); cached && cached->mesh.lock() == mesh) return cached->gpu;
    auto entry = std::make_shared<const CachedMesh>(CachedMesh{mesh, std::make_shared<const GpuMesh>(*mesh)});
    return device.cache().insert(key, entry)->gpu;
}

StylizerTargets::StylizerTargets(int n, int w, int h, bool accelerated) : n(n), width(w), height(h) {
    mapBytes = sizeof(float) * size_t(n) * n;
    pixelBytes = size_t(w) * h * 4 * sizeof(float);
    shadowDepth = texture2D(GL_DEPTH_COMPONENT32F, n, n, "shadow-depth");
    shadowIds = texture2D(GL_R32F, n, n, "shadow-ids");
    scratchDepth = texture2D(GL_DEPTH_COMPONENT32F, n, n, "shadow-depth-part");
    shadowFb = framebuffer("shadow-map", shadowDepth, {&shadowIds}, "the shadow map's");
    scratchFb = framebuffer("shadow-map-part", scratchDepth, {}, "the shadow map's");
    // The accelerated V̄'s min-max levels follow the map in its buffer (no copy of level 0).
    const size_t pyramidBytes = accelerated ? (minMaxLevels(n).entries - size_t(n) * n) * sizeof(uint32_t) : 0;
    scatterDepth = gl::createBuffer(mapBytes + pyramidBytes, nullptr, 0, "scatter-shadow-map");
    part = gl::createBuffer(mapBytes, nullptr, 0, "scatter-shadow-part");
    surface = texture2D(GL_RGBA32F, w, h, "gbuffer-surface");
    colour = texture2D(GL_RGBA32F, w, h, "gbuffer-colour");
    depth = texture2D(GL_DEPTH_COMPONENT32F, w, h, "gbuffer-depth");
    gbufferFb = framebuffer("gbuffer", depth, {&surface, &colour}, "the G-buffer's");
    pixels = gl::createBuffer(pixelBytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "stylized-frame");
    layers = gl::createBuffer(pixelBytes * layout::kStylizeLayers, nullptr, GL_DYNAMIC_STORAGE_BIT, "stylized-aovs");
    m_bytes = 4 * mapBytes + pyramidBytes + pixelBytes * (3 + 1 + layout::kStylizeLayers);
}

std::shared_ptr<const StylizerTargets> targetsFor(GpuDevice& device, int n, int width, int height, bool accelerated, size_t keptBytes) {
    const std::string key = "stylizer-targets/" + std::to_string(n) + "/" + std::to_string(width) + "x" + std::to_string(height) +
                            (accelerated ? "/minmax" : "/naive");
    if (auto cached = device.cache().find<StylizerTargets>(key)) return cached;
    auto made = std::make_shared<const StylizerTargets>(n, width, height, accelerated);
    if (made->bytes() <= keptBytes) device.cache().insert(key, made);
    return made;
}

layout::StylizeParams frameParams(const StylizerScene& scene, const StylizeSettings& settings, const LightMap& map) {
    layout::StylizeParams p;
    const StylizerLight& light = scene.light;
    const Camera& cam = scene.camera;
    p.lightFromWorld = toGl(map.clip);
    p.options = {settings.method == VisibilityMethod::Accelerated ? layout::kVisibilityMinMax : layout::kVisibilityNaive, 0,
                 map.spot ? layout::kStylizerLightSpot : layout::kStylizerLightDirectional, settings.spotSteps};
    p.spot = f4(light.position, std::cos(light.coneDeg * 0.5 * std::numbers::pi / 180));
    p.spotCone = {float(std::cos(light.coneDeg * 0.4 * std::numbers::pi / 180)), 0, 0, 0};  // full light inside 80% of the cone
    const Camera::Frame frame = cam.frame();
    p.eye = f4(cam.eye);
    p.camForward = f4(frame.forward, cam.tanHalfFov());
    p.camRight = f4(frame.right, double(cam.width) / double(cam.height));
    p.camUp = f4(frame.up);
    p.imageSize = {cam.width, cam.height, light.shadowMapSize, settings.steps};
    p.lightDirection = f4(normalize(light.direction));
    p.irradiance = f4(light.irradiance);
    p.medium = {float(scene.medium.extinction), float(scene.medium.albedo),
                scene.medium.phase.type == PhaseType::HenyeyGreenstein ? 1.0f : 0.0f, float(scene.medium.phase.g)};
    p.background = f4(scene.background, std::min(cam.farDist, 3.0e38));
    p.shadow = {2e-5f, scene.occluders.empty() ? 0.0f : 1.0f, float(map.texel), 0};
    return p;
}

void shadowMaps(Frame& f) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);  // leaves are single quads seen from both sides
    renderShadow(f, f.targets.shadowFb, true, [](size_t) { return true; });
}

void shadowEdits(Frame& f, const std::function<float(const Manipulation&)>& threshold, StylizedFrame&) {
    const StylizerTargets& t = f.targets;
    const auto& occluders = f.scene.occluders;
    if (std::none_of(occluders.begin(), occluders.end(), [](const Occluder& o) { return o.manipulation.any(); })) {
        copyToBuffer(t, t.shadowDepth, t.scatterDepth);
        return;
    }
    renderShadow(f, t.scratchFb, false, [&](size_t i) { return !occluders[i].manipulation.any(); });
    copyToBuffer(t, t.scratchDepth, t.scatterDepth);
    for (size_t i = 0; i < occluders.size(); ++i) {
        if (!occluders[i].manipulation.any()) continue;
        renderShadow(f, t.scratchFb, false, [i](size_t j) { return j == i; });
        copyToBuffer(t, t.scratchDepth, t.part);
        editOne(f, i, occluders[i].manipulation.holeProbability > 0 ? threshold(occluders[i].manipulation) : 0.0f);
        foldMinimum(f.device, t.part, t.scatterDepth, t.n);
    }
}

void minMax(Frame& f, StylizedFrame& out) {
    gl::GpuTimer timer;
    {
        gl::GpuTimer::Scope timed(timer);
        if (f.settings.method != VisibilityMethod::Accelerated) return;
        const int n = f.targets.n;
        const auto [sides, offsets, entries] = minMaxLevels(n);
        VOLSTYLE_CHECK(int(sides.size()), <=, layout::kMaxMinMaxLevels);
        glUseProgram(f.device.program(gl::ShaderBuilder("shadow_minmax.comp")).id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMinMax, f.targets.scatterDepth.id());
        for (size_t k = 1; k < sides.size(); ++k) {
            layout::MinMaxParams m;
            m.level = {sides[k - 1], sides[k], offsets[k - 1], offsets[k]};
            f.device.setParams(m);
            const int g = layout::kWorkgroup2D;
            glDispatchCompute(GLuint((sides[k] + g - 1) / g), GLuint((sides[k] + g - 1) / g), 1);
            gl::barrierAfterComputeWrites();
        }
        for (size_t k = 0; k < sides.size(); ++k) {
            layout::Int4& q = f.p.mipOffset[k / 4];
            (k % 4 == 0 ? q.x : k % 4 == 1 ? q.y : k % 4 == 2 ? q.z : q.w) = offsets[k];
        }
        f.p.options.y = int(sides.size());
    }
    out.mipmapGpuMs = timer.elapsedMs();
}

void gBuffer(Frame& f, StylizedFrame& out) {
    const StylizerTargets& t = f.targets;
    const Camera& cam = f.scene.camera;
    const float zero[4] = {0, 0, 0, 0}, one = 1;
    glClearNamedFramebufferfv(t.gbufferFb.id(), GL_COLOR, 0, zero);
    glClearNamedFramebufferfv(t.gbufferFb.id(), GL_COLOR, 1, zero);
    glClearNamedFramebufferfv(t.gbufferFb.id(), GL_DEPTH, 0, &one);
    glBindFramebuffer(GL_FRAMEBUFFER, t.gbufferFb.id());
    glViewport(0, 0, cam.width, cam.height);
    // Clip planes only bound the rasterization; the G-buffer stores true distances.
    const Vec3d lo = f.map.lo, hi = f.map.hi;
    double farthest = 0;
    for (int corner = 0; corner < 8; ++corner)
        farthest = std::max(farthest, length(Vec3d((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z) - cam.eye));
    const double farPlane = std::min(cam.farDist, farthest * 1.01 + 1e-3);
    const double nearPlane = std::max(cam.nearDist, farPlane * 1e-5);
    if (!f.meshes.empty() && farPlane > nearPlane)
        drawOccluders(f, gl::ShaderBuilder("occluders.raster"), cameraClipFromWorld(cam, nearPlane, farPlane), [](size_t) { return true; });
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDisable(GL_DEPTH_TEST);
    if (f.settings.pick) {  // the object id in the G-buffer's colour (0: nothing)
        float texel[4] = {0, 0, 0, 0};
        glGetTextureSubImage(t.colour.id(), 0, f.settings.pick->x, cam.height - 1 - f.settings.pick->y, 0, 1, 1, 1, GL_RGBA, GL_FLOAT,
                             sizeof texel, texel);
        out.pickedOccluder = int(std::lround(texel[3])) - 1;
    }
}

void shade(Frame& f, const std::function<void(layout::StylizeParams&)>& bindMedium, StylizedFrame& out) {
    const StylizerTargets& t = f.targets;
    const Camera& cam = f.scene.camera;
    gl::Texture transfer = texture2D(GL_RGBA32F, 1, 1, "transfer-function");  // bound even when unused
    if (const auto& tf = f.scene.transferFunction) {
        transfer = texture2D(GL_RGBA32F, tf->image->width, tf->image->height, "transfer-function");
        glTextureSubImage2D(transfer.id(), 0, 0, 0, tf->image->width, tf->image->height, GL_RGBA, GL_FLOAT, tf->image->rgba.data());
        f.p.transfer = {tf->mode == TransferFunction::Mode::Multiply ? 1.0f : 2.0f, float(tf->depthNear), float(tf->depthFar), 0};
    }
    if (f.scene.volume) f.p.medium.x = 0;  // the grid's σt replaces the homogeneous one (a spot's surfaces: T_l instead)
    bindMedium(f.p);  // inside the shading time
    // A pick reads one pixel back: only that pixel is shaded (a 4096² pick costs one ray).
    const bool onePixel = f.settings.pick && f.settings.pickOnly;
    f.p.pixelOrigin = {0, 0, 0, 0};
    if (onePixel) f.p.pixelOrigin = {f.settings.pick->x, f.settings.pick->y, 0, 0};
    f.device.setParams(f.p);
    glBindTextureUnit(layout::kUnitTransferFunction, transfer.id());
    glBindTextureUnit(layout::kUnitShadowDepth, t.shadowDepth.id());
    glBindTextureUnit(layout::kUnitGBufferSurface, t.surface.id());
    glBindTextureUnit(layout::kUnitGBufferColour, t.colour.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingScatterDepth, t.scatterDepth.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMinMax, t.scatterDepth.id());
    glUseProgram(f.device.program(gl::ShaderBuilder("stylize.comp")).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingImageOut, t.pixels.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingLayersOut, t.layers.id());
    const int g = layout::kWorkgroup2D;
    gl::GpuTimer timer;
    {
        gl::GpuTimer::Scope timed(timer);
        if (onePixel) glDispatchCompute(1, 1, 1);
        else glDispatchCompute(GLuint((cam.width + g - 1) / g), GLuint((cam.height + g - 1) / g), 1);
    }
    gl::barrierAfterComputeWrites();
    f.device.finish();
    out.shadeGpuMs = timer.elapsedMs();
}

void readBack(Frame& f, StylizedFrame& out) {
    const StylizerTargets& t = f.targets;
    const StylizeSettings& settings = f.settings;
    const Camera& cam = f.scene.camera;
    const size_t bytes = t.pixelBytes, pixelCount = size_t(cam.width) * cam.height;
    const int n = t.n;
    if (settings.pick && settings.pickOnly) {
        // One pixel of the frame and of each AOV plane (the planes are RGBA, rows bottom-up as
        // the frame's: the same offset in each).
        const size_t at = (size_t(settings.pick->y) * size_t(cam.width) + size_t(settings.pick->x)) * 4 * sizeof(float);
        const auto pixelOf = [&](const gl::Buffer& buffer, size_t plane) {
            Image img(1, 1);
            glGetNamedBufferSubData(buffer.id(), GLintptr(plane * bytes + at), GLsizeiptr(4 * sizeof(float)), img.rgba.data());
            return img;
        };
        out.frame = pixelOf(t.pixels, 0);
        out.scattering = readChannelPlane(pixelOf(t.layers, 0).rgba, 1, 1, 0, false);
        out.averageVisibility = readChannelPlane(pixelOf(t.layers, 0).rgba, 1, 1, 3, true);
        out.linearDepth = readChannelPlane(pixelOf(t.layers, 1).rgba, 1, 1, 0, true);
    } else {
        out.frame = Image(cam.width, cam.height);
        glGetNamedBufferSubData(t.pixels.id(), 0, GLsizeiptr(bytes), out.frame.rgba.data());
    }
    if (settings.readAovs && !(settings.pick && settings.pickOnly)) {
        std::vector<float> plane(pixelCount * 4);
        glGetNamedBufferSubData(t.layers.id(), 0, GLsizeiptr(bytes), plane.data());
        out.scattering = readChannelPlane(plane, cam.width, cam.height, 0, false);
        out.averageVisibility = readChannelPlane(plane, cam.width, cam.height, 3, true);
        glGetNamedBufferSubData(t.layers.id(), GLintptr(bytes), GLsizeiptr(bytes), plane.data());
        out.linearDepth = readChannelPlane(plane, cam.width, cam.height, 0, true);
    }
    auto mapImage = [n](const std::vector<float>& depthRows) {
        Image img(n, n);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                float* px = img.pixel(x, n - 1 - y);  // row 0 on top, as every image
                px[0] = px[1] = px[2] = depthRows[size_t(y) * n + x];
                px[3] = 1;
            }
        return img;
    };
    if (settings.readShadowMaps) {
        std::vector<float> shadow(size_t(n) * n);
        glGetTextureImage(t.shadowDepth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(t.mapBytes), shadow.data());
        out.shadowMap = mapImage(shadow);
        glGetNamedBufferSubData(t.scatterDepth.id(), 0, GLsizeiptr(t.mapBytes), shadow.data());
        out.modifiedShadowMap = mapImage(shadow);
    }
}

}  // namespace volstyle::core::stylize
