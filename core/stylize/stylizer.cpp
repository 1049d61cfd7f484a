#include "core/stylize/stylizer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/render/gl_convert.h"
#include "core/shaders/layout.h"
#include "core/stylize/keyframes.h"
#include "core/stylize/light_map.h"
#include "core/stylize/medium_gpu.h"
#include "core/stylize/morphology_gpu.h"
#include "core/stylize/tf_anchors.h"

namespace volstyle::core {

namespace {

gl::Texture texture2D(GLenum format, int w, int h, const char* label) { return gl::createTexture2D(format, w, h, GL_NEAREST, label); }

/// An occluder's mesh on the GPU: interleaved position + normal, 32-bit indices.
struct GpuMesh {
    gl::Buffer vertices, indices;
    gl::VertexArray vao;
    GLsizei indexCount = 0;

    explicit GpuMesh(const Mesh& m) {
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

/// Frame buffers up to this size stay allocated for the next frame (a 1080p frame's are 33 MB);
/// larger ones are freed once read.
constexpr size_t kKeptFrameBytes = size_t(64) << 20;

}  // namespace

struct Stylizer::Gpu {
    gl::Buffer pixels, layers;
    size_t pixelBytes = 0;
    std::map<std::tuple<double, int, double, uint32_t>, float> holeThresholds;  // calibrations, reused
    /// GPU copies of the meshes of recent frames, kept while their mesh lives: a live stream
    /// re-renders the same scene with another camera, time or manipulation, and uploading a
    /// large mesh every frame would cost more than the frame.
    struct CachedMesh {
        std::weak_ptr<const Mesh> mesh;
        std::shared_ptr<GpuMesh> gpu;
    };
    std::map<const Mesh*, CachedMesh> meshes;
    StylizerMediumCache medium;  ///< the heterogeneous medium's textures

    std::shared_ptr<GpuMesh> mesh(const std::shared_ptr<const Mesh>& m) {
        std::erase_if(meshes, [](const auto& entry) { return entry.second.mesh.expired(); });
        auto it = meshes.find(m.get());
        if (it == meshes.end()) it = meshes.emplace(m.get(), CachedMesh{m, std::make_shared<GpuMesh>(*m)}).first;
        return it->second.gpu;
    }

    float threshold(const Manipulation& m) {
        const auto key = std::make_tuple(m.holeProbability, m.holeOctaves, m.holePersistence, m.holeSeed);
        auto it = holeThresholds.find(key);
        if (it == holeThresholds.end()) {
            if (holeThresholds.size() > 256) holeThresholds.clear();
            it = holeThresholds.emplace(key, holeThreshold(m.holeProbability, m.holeOctaves, m.holePersistence, m.holeSeed)).first;
        }
        return it->second;
    }
};

namespace {

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

/// The min-max mipmap (shadow_minmax.comp) of the n×n map at the start of `depth`, written into the
/// same buffer after the map (minMaxLevels(n).entries in all; common/min_max_entry.glsl): level 0
/// is the map itself. The levels' offsets go to `p.mipOffset`, their count to `p.options.y`.
void buildMinMaxMipmap(GpuDevice& device, const gl::Buffer& depth, int n, layout::StylizeParams& p) {
    const auto [sides, offsets, entries] = minMaxLevels(n);
    VOLSTYLE_CHECK(int(sides.size()), <=, layout::kMaxMinMaxLevels);
    glUseProgram(device.program(gl::ShaderBuilder("shadow_minmax.comp")).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMinMax, depth.id());
    for (size_t k = 1; k < sides.size(); ++k) {
        layout::MinMaxParams m;
        m.level = {sides[k - 1], sides[k], offsets[k - 1], offsets[k]};
        device.setParams(m);
        const int g = layout::kWorkgroup2D;
        glDispatchCompute(GLuint((sides[k] + g - 1) / g), GLuint((sides[k] + g - 1) / g), 1);
        gl::barrierAfterComputeWrites();
    }
    for (size_t k = 0; k < sides.size(); ++k) {
        layout::Int4& q = p.mipOffset[k / 4];
        (k % 4 == 0 ? q.x : k % 4 == 1 ? q.y : k % 4 == 2 ? q.z : q.w) = offsets[k];
    }
    p.options.y = int(sides.size());
}

}  // namespace

Stylizer::Stylizer(GpuDevice& device) : m_device(device), m_gpu(std::make_unique<Gpu>()) {}
Stylizer::~Stylizer() = default;

double Stylizer::estimatedLookups(const StylizerScene& scene, const StylizeSettings& settings) {
    const double pixels = double(scene.camera.width) * scene.camera.height;
    const double texels = double(scene.light.shadowMapSize) * scene.light.shadowMapSize;
    double lookups = pixels * (settings.method == VisibilityMethod::Naive ? settings.steps : kAcceleratedLookupsPerRay);
    if (scene.light.type == StylizerLightType::Spot) lookups += pixels * settings.spotSteps;
    if (scene.volume) lookups += pixels * 3.0 * scene.volume->steps;  // a shadow-map and two texture lookups a step
    // A TF with anchored constraints is compiled for every frame: about 4 µs a texel and
    // diffusion layer on one core (bench/tf_bench), some 400 lookups' worth.
    for (const TransferFunction* tf : scene.transferFunctions()) {
        if (!tf->hasAnchors()) continue;
        double diffusion = 0;
        for (const TfLayer& l : tf->layers) diffusion += l.kind == TfLayerKind::Diffusion ? 1 : 0;
        lookups += 400.0 * tf->width * tf->height * diffusion;
    }
    const LightMap map = lightMapOf(scene);
    for (size_t i = 0; i < scene.occluders.size(); ++i) {
        const Manipulation& m = scene.occluders[i].manipulation;
        if (!m.any()) continue;
        double perTexel = 4;  // drawn alone, copied, folded in
        if (m.closingRadius > 0) perTexel += m.closingShape == MorphShape::Disc && m.closingRadius <= kExactDiscRadius ? 6.0 * (2 * m.closingRadius + 1) : 16;
        if (m.dilationLength > 0) perTexel += dilationTexels(map, scene, i) + (m.erosionPx > 0 ? 6 : 0);
        if (m.holeProbability > 0) perTexel += 8.0 * m.holeOctaves;
        lookups += texels * perTexel;
    }
    return lookups;
}

StylizedFrame Stylizer::render(const StylizerScene& scene, const StylizeSettings& settings) {
    scene.validate();
    // The TFs to blend, weighted: the two keys' around the scene's time on a path, else its own.
    std::vector<std::pair<TransferFunction, double>> tfs;
    if (!scene.keyframes.empty() && scene.keyframes.front().transferFunction) {
        const PathPosition at = pathPosition(scene.keyframes, scene.time);
        tfs.push_back({*scene.keyframes[at.before].transferFunction, 1 - at.weight});
        if (at.weight > 0) tfs.push_back({*scene.keyframes[at.after].transferFunction, at.weight});
    } else if (scene.transferFunction) {
        tfs.push_back({*scene.transferFunction, 1});
    }
    const bool anchored = std::any_of(tfs.begin(), tfs.end(), [](const auto& t) { return t.first.hasAnchors(); });
    // The TF the frame applies: compiled where it is layers (anchors moved first), blended.
    auto blended = [&] {
        TransferFunction out = tfs.front().first;
        for (auto& [tf, w] : tfs)
            if (!tf.layers.empty() && (!tf.image || tf.hasAnchors())) compileTransferFunction(tf);
        out.layers.clear();
        out.image = tfs.size() == 1 ? tfs.front().first.image
                                    : std::make_shared<const Image>(blendImages(*tfs[0].first.image, *tfs[1].first.image, tfs[1].second));
        return out;
    };
    StylizerScene s = scene;
    s.transferFunction.reset();
    if (!anchored) {
        if (!tfs.empty()) s.transferFunction = blended();
        StylizedFrame f = renderPass(s, settings);
        f.transferFunction = s.transferFunction;
        return f;
    }
    // Anchored constraints: where they are depends on this frame's V̄ and depths, so the frame is
    // rendered without the TF (and with its AOVs) and the TF applied to it.
    StylizeSettings withAovs = settings;
    withAovs.readAovs = true;
    withAovs.pickOnly = false;  // the anchors read the AOVs where they are
    StylizedFrame f = renderPass(s, withAovs);
    const auto t = Clock::now();
    for (auto& [tf, w] : tfs) resolveAnchors(tf, scene, f);
    f.transferFunction = blended();
    applyTransferFunction(*f.transferFunction, f);
    if (settings.pick && settings.pickOnly)
        for (Image* img : {&f.frame, &f.scattering, &f.averageVisibility, &f.linearDepth}) {
            Image one(1, 1);
            std::copy_n(img->pixel(settings.pick->x, settings.pick->y), 4, one.rgba.data());
            *img = std::move(one);
        }
    const double ms = msSince(t);
    f.shadeMs += ms, f.totalMs += ms;
    return f;
}

StylizedFrame Stylizer::renderPass(const StylizerScene& scene, const StylizeSettings& settings) {
    VOLSTYLE_CHECK(m_device.isOwnedByThisThread(), ==, true);  // the scene: validated by render()
    settings.validate();
    if (settings.pick && !(settings.pick->x >= 0 && settings.pick->y >= 0 && settings.pick->x < scene.camera.width &&
                           settings.pick->y < scene.camera.height))
        throw InvalidArgument("/x, /y: the pixel must be inside the " + std::to_string(scene.camera.width) + "×" +
                              std::to_string(scene.camera.height) + " image");
    const auto t0 = Clock::now();
    StylizedFrame out;
    const Camera& cam = scene.camera;
    const int n = scene.light.shadowMapSize;

    std::vector<std::shared_ptr<GpuMesh>> meshes;
    for (const Occluder& o : scene.occluders) meshes.push_back(m_gpu->mesh(o.mesh));
    const bool hasOccluders = !meshes.empty();
    const LightMap map = lightMapOf(scene);
    const Vec3d lo = map.lo, hi = map.hi;

    layout::StylizeParams p;
    const StylizerLight& light = scene.light;
    const bool spot = map.spot;
    const Vec3d toLight = normalize(light.direction);
    const Mat4& lightClip = map.clip;
    const double spotTan = map.spotTan;
    p.lightFromWorld = toGl(lightClip);
    p.options = {settings.method == VisibilityMethod::Accelerated ? layout::kVisibilityMinMax : layout::kVisibilityNaive, 0,
                 spot ? layout::kStylizerLightSpot : layout::kStylizerLightDirectional, settings.spotSteps};
    p.spot = f4(light.position, std::cos(light.coneDeg * 0.5 * std::numbers::pi / 180));
    p.spotCone = {float(std::cos(light.coneDeg * 0.4 * std::numbers::pi / 180)), 0, 0, 0};  // full light inside 80% of the cone
    const Camera::Frame f = cam.frame();
    p.eye = f4(cam.eye);
    p.camForward = f4(f.forward, cam.tanHalfFov());
    p.camRight = f4(f.right, double(cam.width) / double(cam.height));
    p.camUp = f4(f.up);
    p.imageSize = {cam.width, cam.height, n, settings.steps};
    p.lightDirection = f4(toLight);
    p.irradiance = f4(scene.light.irradiance);
    p.medium = {float(scene.medium.extinction), float(scene.medium.albedo),
                scene.medium.phase.type == PhaseType::HenyeyGreenstein ? 1.0f : 0.0f, float(scene.medium.phase.g)};
    p.background = f4(scene.background, std::min(cam.farDist, 3.0e38));
    const double texel = map.texel;
    p.shadow = {2e-5f, hasOccluders ? 1.0f : 0.0f, float(texel), 0};

    // Draws the occluders `which` accepts (by index) with `builder` from `clipFromWorld`.
    auto drawOccluders = [&](const gl::ShaderBuilder& builder, const Mat4& clipFromWorld, const auto& which) {
        glUseProgram(m_device.program(builder).id());
        p.clipFromWorld = toGl(clipFromWorld);
        for (size_t i = 0; i < meshes.size(); ++i) {
            if (!which(i)) continue;
            p.worldFromObject = toGl(scene.occluders[i].worldFromObject);
            p.surface = f4(scene.occluders[i].colour, double(i + 1));
            m_device.setParams(p);
            glBindVertexArray(meshes[i]->vao.id());
            glDrawElements(GL_TRIANGLES, meshes[i]->indexCount, GL_UNSIGNED_INT, nullptr);
        }
        glBindVertexArray(0);
    };
    auto all = [](size_t) { return true; };
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);  // leaves are single quads seen from both sides

    // 1. The light's shadow maps. The unmodified one (depth, and object ids for the per-object
    //    manipulations) shadows surfaces; the scattering's starts from the objects left alone,
    //    and each manipulated object is drawn alone, edited and folded in by minimum (Sec. 4).
    auto t = Clock::now();
    const gl::ShaderBuilder shadowPass = gl::ShaderBuilder("occluders.raster").define("VOLSTYLE_PASS_SHADOW", 1);
    auto renderShadow = [&](const gl::Texture& depthTarget, const gl::Texture* ids, const auto& which) {
        gl::Framebuffer fb = gl::createFramebuffer("shadow-map");
        glNamedFramebufferTexture(fb.id(), GL_DEPTH_ATTACHMENT, depthTarget.id(), 0);
        if (ids) glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT0, ids->id(), 0);
        else glNamedFramebufferDrawBuffer(fb.id(), GL_NONE);
        gl::checkFramebufferComplete(fb, "the shadow map's");
        const float zero[4] = {0, 0, 0, 0}, one = 1;
        if (ids) glClearNamedFramebufferfv(fb.id(), GL_COLOR, 0, zero);
        glClearNamedFramebufferfv(fb.id(), GL_DEPTH, 0, &one);
        glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
        glViewport(0, 0, n, n);
        if (hasOccluders) drawOccluders(shadowPass, lightClip, which);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    };
    const size_t mapBytes = sizeof(float) * size_t(n) * n;
    auto copyToBuffer = [&](const gl::Texture& depthMap, const gl::Buffer& into) {  // on the GPU, no round trip
        glBindBuffer(GL_PIXEL_PACK_BUFFER, into.id());
        glGetTextureImage(depthMap.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(mapBytes), nullptr);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    };
    gl::Texture shadowDepth = texture2D(GL_DEPTH_COMPONENT32F, n, n, "shadow-depth");
    gl::Texture shadowIds = texture2D(GL_R32F, n, n, "shadow-ids");
    renderShadow(shadowDepth, &shadowIds, all);
    // The accelerated V̄'s min-max levels follow the map in its buffer (no copy of level 0).
    const size_t pyramidBytes = settings.method == VisibilityMethod::Accelerated ? (minMaxLevels(n).entries - size_t(n) * n) * sizeof(uint32_t) : 0;
    gl::Buffer scatterDepth = gl::createBuffer(mapBytes + pyramidBytes, nullptr, 0, "scatter-shadow-map");
    bool manipulated = false;
    for (const Occluder& o : scene.occluders) manipulated = manipulated || o.manipulation.any();
    if (!manipulated) {
        copyToBuffer(shadowDepth, scatterDepth);
    } else {
        gl::Texture scratchMap = texture2D(GL_DEPTH_COMPONENT32F, n, n, "shadow-depth-part");
        renderShadow(scratchMap, nullptr, [&](size_t i) { return !scene.occluders[i].manipulation.any(); });
        copyToBuffer(scratchMap, scatterDepth);
        gl::Buffer part = gl::createBuffer(mapBytes, nullptr, 0, "scatter-shadow-part");
        for (size_t i = 0; i < scene.occluders.size(); ++i) {
            const Manipulation& m = scene.occluders[i].manipulation;
            if (!m.any()) continue;
            renderShadow(scratchMap, nullptr, [i](size_t j) { return j == i; });
            copyToBuffer(scratchMap, part);
            closeDepthBuffer(m_device, part, n, m.closingRadius, m.closingShape);
            const auto& [objectLo, objectHi] = map.objectBounds[i];
            if (m.dilationLength > 0) {
                dilateEpipolarBuffer(m_device, part, n, epipoleOf(lightClip, cam.eye, n), dilationTexels(map, scene, i));
                erodeBoxBuffer(m_device, part, n, m.erosionPx);
            }
            if (m.holeProbability > 0) {
                HoleMap h = holeMapOf(lightClip, spot, spotTan * length((objectLo + objectHi) * 0.5 - light.position), n, m.holeFrequency);
                h.threshold = m_gpu->threshold(m);
                holeTimeOffset(scene.time, m.holeSpeed, h.offsetX, h.offsetY);
                h.octaves = m.holeOctaves;
                h.persistence = m.holePersistence;
                h.seed = m.holeSeed;
                cutHolesBuffer(m_device, part, n, h);
            }
            foldMinimum(m_device, part, scatterDepth, n);
        }
    }
    m_device.finish();
    out.shadowMs = msSince(t);
    t = Clock::now();
    gl::GpuTimer mipmapTimer, shadeTimer;
    {
        gl::GpuTimer::Scope timed(mipmapTimer);
        if (settings.method == VisibilityMethod::Accelerated) buildMinMaxMipmap(m_device, scatterDepth, n, p);
    }
    m_device.finish();
    out.mipmapMs = msSince(t);
    out.mipmapGpuMs = mipmapTimer.elapsedMs();

    // 2. The camera's G-buffer: normal and distance, colour and id.
    t = Clock::now();
    gl::Texture surface = texture2D(GL_RGBA32F, cam.width, cam.height, "gbuffer-surface");
    gl::Texture colour = texture2D(GL_RGBA32F, cam.width, cam.height, "gbuffer-colour");
    gl::Texture depth = texture2D(GL_DEPTH_COMPONENT32F, cam.width, cam.height, "gbuffer-depth");
    {
        gl::Framebuffer fb = gl::createFramebuffer("gbuffer");
        glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT0, surface.id(), 0);
        glNamedFramebufferTexture(fb.id(), GL_COLOR_ATTACHMENT1, colour.id(), 0);
        glNamedFramebufferTexture(fb.id(), GL_DEPTH_ATTACHMENT, depth.id(), 0);
        const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
        glNamedFramebufferDrawBuffers(fb.id(), 2, buffers);
        gl::checkFramebufferComplete(fb, "the G-buffer's");
        const float zero[4] = {0, 0, 0, 0}, one = 1;
        glClearNamedFramebufferfv(fb.id(), GL_COLOR, 0, zero);
        glClearNamedFramebufferfv(fb.id(), GL_COLOR, 1, zero);
        glClearNamedFramebufferfv(fb.id(), GL_DEPTH, 0, &one);
        glBindFramebuffer(GL_FRAMEBUFFER, fb.id());
        glViewport(0, 0, cam.width, cam.height);
        // Clip planes only bound the rasterization; the G-buffer stores true distances.
        double farthest = 0;
        for (int corner = 0; corner < 8; ++corner)
            farthest = std::max(farthest, length(Vec3d((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y,
                                                       (corner & 4) ? hi.z : lo.z) - cam.eye));
        const double farPlane = std::min(cam.farDist, farthest * 1.01 + 1e-3);
        const double nearPlane = std::max(cam.nearDist, farPlane * 1e-5);
        if (hasOccluders && farPlane > nearPlane)
            drawOccluders(gl::ShaderBuilder("occluders.raster"), cameraClipFromWorld(cam, nearPlane, farPlane), all);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }
    glDisable(GL_DEPTH_TEST);
    if (settings.pick) {  // the object id in the G-buffer's colour (0: nothing)
        float texel[4] = {0, 0, 0, 0};
        glGetTextureSubImage(colour.id(), 0, settings.pick->x, cam.height - 1 - settings.pick->y, 0, 1, 1, 1, GL_RGBA, GL_FLOAT,
                             sizeof texel, texel);
        out.pickedOccluder = int(std::lround(texel[3])) - 1;
    }
    m_device.finish();
    out.gbufferMs = msSince(t);

    // 3. Per pixel: V̄ and the frame.
    t = Clock::now();
    const size_t pixelCount = size_t(cam.width) * cam.height, bytes = pixelCount * 4 * sizeof(float);
    if (bytes > m_gpu->pixelBytes) {
        m_gpu->pixels = gl::createBuffer(bytes, nullptr, GL_DYNAMIC_STORAGE_BIT, "stylized-frame");
        m_gpu->layers = gl::createBuffer(bytes * layout::kStylizeLayers, nullptr, GL_DYNAMIC_STORAGE_BIT, "stylized-aovs");
        m_gpu->pixelBytes = bytes;
    }
    gl::Texture transfer = texture2D(GL_RGBA32F, 1, 1, "transfer-function");  // bound even when unused
    if (const auto& tf = scene.transferFunction) {
        transfer = texture2D(GL_RGBA32F, tf->image->width, tf->image->height, "transfer-function");
        glTextureSubImage2D(transfer.id(), 0, 0, 0, tf->image->width, tf->image->height, GL_RGBA, GL_FLOAT, tf->image->rgba.data());
        p.transfer = {tf->mode == TransferFunction::Mode::Multiply ? 1.0f : 2.0f, float(tf->depthNear), float(tf->depthFar), 0};
    }
    if (scene.volume) p.medium.x = 0;  // the grid's σt replaces the homogeneous one (a spot's surfaces: T_l instead)
    (void)m_gpu->medium.bind(m_device, scene.volume, p);  // inside the shading time
    m_device.setParams(p);
    glBindTextureUnit(layout::kUnitTransferFunction, transfer.id());
    glBindTextureUnit(layout::kUnitShadowDepth, shadowDepth.id());
    glBindTextureUnit(layout::kUnitGBufferSurface, surface.id());
    glBindTextureUnit(layout::kUnitGBufferColour, colour.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingScatterDepth, scatterDepth.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingMinMax, scatterDepth.id());
    glUseProgram(m_device.program(gl::ShaderBuilder("stylize.comp")).id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingImageOut, m_gpu->pixels.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingLayersOut, m_gpu->layers.id());
    const int g = layout::kWorkgroup2D;
    {
        gl::GpuTimer::Scope timed(shadeTimer);
        glDispatchCompute(GLuint((cam.width + g - 1) / g), GLuint((cam.height + g - 1) / g), 1);
    }
    gl::barrierAfterComputeWrites();
    m_device.finish();
    out.shadeMs = msSince(t);
    out.shadeGpuMs = shadeTimer.elapsedMs();
    t = Clock::now();
    if (settings.pick && settings.pickOnly) {
        // One pixel of the frame and of each AOV plane (the planes are RGBA, rows bottom-up as
        // the frame's: the same offset in each).
        const size_t at = (size_t(settings.pick->y) * size_t(cam.width) + size_t(settings.pick->x)) * 4 * sizeof(float);
        const auto pixelOf = [&](const gl::Buffer& buffer, size_t plane) {
            Image img(1, 1);
            glGetNamedBufferSubData(buffer.id(), GLintptr(plane * bytes + at), GLsizeiptr(4 * sizeof(float)), img.rgba.data());
            return img;
        };
        out.frame = pixelOf(m_gpu->pixels, 0);
        out.scattering = readChannelPlane(pixelOf(m_gpu->layers, 0).rgba, 1, 1, 0, false);
        out.averageVisibility = readChannelPlane(pixelOf(m_gpu->layers, 0).rgba, 1, 1, 3, true);
        out.linearDepth = readChannelPlane(pixelOf(m_gpu->layers, 1).rgba, 1, 1, 0, true);
    } else {
        out.frame = Image(cam.width, cam.height);
        glGetNamedBufferSubData(m_gpu->pixels.id(), 0, GLsizeiptr(bytes), out.frame.rgba.data());
    }
    if (settings.readAovs && !(settings.pick && settings.pickOnly)) {
        std::vector<float> plane(pixelCount * 4);
        glGetNamedBufferSubData(m_gpu->layers.id(), 0, GLsizeiptr(bytes), plane.data());
        out.scattering = readChannelPlane(plane, cam.width, cam.height, 0, false);
        out.averageVisibility = readChannelPlane(plane, cam.width, cam.height, 3, true);
        glGetNamedBufferSubData(m_gpu->layers.id(), GLintptr(bytes), GLsizeiptr(bytes), plane.data());
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
        glGetTextureImage(shadowDepth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(mapBytes), shadow.data());
        out.shadowMap = mapImage(shadow);
        glGetNamedBufferSubData(scatterDepth.id(), 0, GLsizeiptr(mapBytes), shadow.data());
        out.modifiedShadowMap = mapImage(shadow);
    }
    out.readbackMs = msSince(t);
    if (bytes > kKeptFrameBytes) {  // a one-off large frame: its buffers go back now, not at the next frame
        m_gpu->pixels = {};
        m_gpu->layers = {};
        m_gpu->pixelBytes = 0;
    }
    out.totalMs = msSince(t0);
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory while stylizing");
    return out;
}

}  // namespace volstyle::core
