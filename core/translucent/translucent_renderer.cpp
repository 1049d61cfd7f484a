#include "core/translucent/translucent_renderer.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>

#include "core/base/errors.h"
#include "core/gl/object.h"
#include "core/gl/shader_builder.h"
#include "core/scene/environment_lobes.h"
#include "core/render/gl_convert.h"
#include "core/shaders/layout.h"
#include "core/stylize/light_map.h"
#include "core/translucent/perturbation.h"

namespace volstyle::core {
namespace {

using Clock = std::chrono::steady_clock;

/// Unit vectors a, b completing the unit w to an orthonormal frame.
void frameAround(const Vec3d& w, Vec3d& a, Vec3d& b) {
    const Vec3d t = std::abs(w.y) < 0.9 ? Vec3d(0, 1, 0) : Vec3d(1, 0, 0);
    a = normalize(cross(t, w));
    b = cross(w, a);
}

/// The volume's box (index space [-0.5, dims - 0.5]) in world space; corner i has bit 0 for x,
/// bit 1 for y, bit 2 for z.
std::array<Vec3d, 8> boxCorners(const GpuVolume& volume) {
    const Int3 n = volume.dims();
    std::array<Vec3d, 8> c;
    for (int i = 0; i < 8; ++i)
        c[size_t(i)] = volume.worldFromIndex().applyPoint({(i & 1) ? n.x - 0.5 : -0.5, (i & 2) ? n.y - 0.5 : -0.5, (i & 4) ? n.z - 0.5 : -0.5});
    return c;
}

/// The convex polygon where the plane s·x = t cuts the box, its corners in order around it (empty
/// when the plane misses the box).
std::vector<Vec3d> slicePolygon(const std::array<Vec3d, 8>& corners, const Vec3d& s, double t) {
    static constexpr int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    std::vector<Vec3d> points;
    for (const auto& e : kEdges) {
        const Vec3d& p = corners[size_t(e[0])];
        const Vec3d& q = corners[size_t(e[1])];
        const double dp = dot(p, s) - t, dq = dot(q, s) - t;
        if ((dp < 0) != (dq < 0)) points.push_back(p + (q - p) * (dp / (dp - dq)));
    }
    if (points.size() < 3) return {};
    Vec3d centre;
    for (const Vec3d& p : points) centre += p;
    centre = centre / double(points.size());
    Vec3d a, b;
    frameAround(s, a, b);
    std::sort(points.begin(), points.end(), [&](const Vec3d& p, const Vec3d& q) {
        return std::atan2(dot(p - centre, b), dot(p - centre, a)) < std::atan2(dot(q - centre, b), dot(q - centre, a));
    });
    return points;
}

/// p(cos θ) with cos θ = ω_l·(−ω) (SPEC §1), as the single-scattering renderer's.
double phaseOf(const Phase& phase, double cosTheta) {
    const double inv4pi = 1 / (4 * std::numbers::pi);
    if (phase.type == PhaseType::Isotropic) return inv4pi;
    const double g = phase.g, denom = 1 + g * g + 2 * g * cosTheta;
    return inv4pi * (1 - g * g) / (denom * std::sqrt(std::max(denom, 1e-12)));
}

/// The light's view of the box: a square frame orthogonal to its travel, uv in [0, 1]².
struct LightFrame {
    Vec3d a, b, travel;  ///< the frame's axes, and the direction light travels (away from the light)
    double a0 = 0, b0 = 0, extent = 1;
    Mat4 uvFromWorld() const {
        Mat4 m;
        for (int c = 0; c < 3; ++c) m(0, c) = a[c] / extent, m(1, c) = b[c] / extent, m(2, c) = 0;
        m(0, 3) = -a0 / extent, m(1, 3) = -b0 / extent, m(2, 2) = 0, m(2, 3) = 0;
        return m;
    }
    Mat4 clipFromWorld() const {  // uv to [-1, 1]², depth 0
        Mat4 m = uvFromWorld();
        for (int c = 0; c < 4; ++c) m(0, c) *= 2, m(1, c) *= 2;
        m(0, 3) -= 1, m(1, 3) -= 1;
        return m;
    }
};

/// `margin` (world) around the box's outline: light passing beside the box is blurred into it
/// from as far as the indirect light's cone reaches through the box.
LightFrame lightFrame(const std::array<Vec3d, 8>& corners, const Vec3d& towardLight, int texels, double margin) {
    LightFrame f;
    f.travel = -normalize(towardLight);
    frameAround(f.travel, f.a, f.b);
    double a1 = -1e300, b1 = -1e300;
    f.a0 = f.b0 = 1e300;
    for (const Vec3d& p : corners) {
        f.a0 = std::min(f.a0, dot(p, f.a)), a1 = std::max(a1, dot(p, f.a));
        f.b0 = std::min(f.b0, dot(p, f.b)), b1 = std::max(b1, dot(p, f.b));
    }
    // Square, centred, the margin and one texel more on each side so the box never touches the edge.
    const double side = std::max({a1 - f.a0, b1 - f.b0, 1e-9}) + 2 * margin;
    f.extent = side * texels / std::max(texels - 2, 1);
    f.a0 = 0.5 * (f.a0 + a1) - 0.5 * f.extent;
    f.b0 = 0.5 * (f.b0 + b1) - 0.5 * f.extent;
    return f;
}

/// The light frame's four corners on the plane s·x = t (the light pass covers every texel).
std::vector<Vec3d> lightQuad(const LightFrame& f, const Vec3d& s, double t) {
    std::vector<Vec3d> quad;
    for (auto [u, v] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}}) {
        const double a = f.a0 + u * f.extent, b = f.b0 + v * f.extent;
        const double c = (t - a * dot(f.a, s) - b * dot(f.b, s)) / dot(f.travel, s);
        quad.push_back(f.a * a + f.b * b + f.travel * c);
    }
    return quad;
}

/// What lies behind the medium along the pixel's ray: the plate, the lobes, the map or the colour.
Vec3d backgroundAt(const Lighting& l, const Camera& cam, int x, int y, const std::vector<Vec3d>& lobeRadiance,
                   const LobeBasis* basis) {
    const Background& bg = l.background;
    if (bg.plate) {
        const float* p = bg.plate->pixel(x, y);
        return {p[0], p[1], p[2]};
    }
    if (!basis && !bg.environment) return bg.color;  // no direction needed
    const Vec3d dir = cam.rayDirection(x, y);
    if (basis) {
        const int cell = basis->cellOf(dir);
        if (cell >= 0) return lobeRadiance[size_t(cell)];
    }
    return bg.environment ? sampleLatLong(*bg.environment, dir) : bg.color;
}

}  // namespace

/// The eye buffer and the two pairs of light buffers (direct, indirect), kept between frames of
/// the same sizes; the slice vertices' buffer; the phase table.
struct TranslucentRenderer::Targets {
    int width = 0, height = 0, lightSide = 0;
    gl::Texture eye;
    gl::Framebuffer eyeFb;
    gl::Texture direct[2], indirect[2];
    gl::Framebuffer lightFb[2];
    gl::Buffer vertices;
    gl::VertexArray vao;
    gl::Texture phase;
    gl::Texture noise;  ///< the perturbation's, for `noiseSeed`
    uint32_t noiseSeed = 0;
    bool hasNoise = false;
};

TranslucentRenderer::TranslucentRenderer(GpuDevice& device) : m_device(device), m_targets(std::make_unique<Targets>()) {
    Targets& t = *m_targets;
    t.vertices = gl::createBuffer(8 * 3 * sizeof(float), nullptr, GL_DYNAMIC_STORAGE_BIT, "slice-vertices");
    t.vao = gl::createVertexArray("slice");
    glVertexArrayVertexBuffer(t.vao.id(), 0, t.vertices.id(), 0, 3 * sizeof(float));
    glEnableVertexArrayAttrib(t.vao.id(), 0);
    glVertexArrayAttribFormat(t.vao.id(), 0, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(t.vao.id(), 0, 0);
    t.phase = gl::createTexture2D(GL_R32F, layout::kPhaseTableSize, 1, GL_LINEAR, "phase-table");
}

TranslucentRenderer::~TranslucentRenderer() = default;

Image TranslucentRenderer::render(GpuVolume& volume, const Camera& cam, const Lighting& lighting,
                                  const TranslucentSettings& settings, TranslucentStats* statsOut, Image* medium,
                                  const WorkBudget& budget) {
    VOLSTYLE_CHECK(m_device.isOwnedByThisThread(), ==, true);
    cam.validate();
    lighting.validate();
    settings.validate();
    if (lighting.background.plate && (lighting.background.plate->width != cam.width || lighting.background.plate->height != cam.height))
        throw InvalidArgument("the background plate is " + std::to_string(lighting.background.plate->width) + "x" +
                              std::to_string(lighting.background.plate->height) + " but the camera renders " +
                              std::to_string(cam.width) + "x" + std::to_string(cam.height));
    const auto t0 = Clock::now();
    Targets& t = *m_targets;
    const int side = settings.lightBufferSize;

    // Targets of this frame's sizes.
    if (t.width != cam.width || t.height != cam.height) {
        t.eye = gl::createTexture2D(GL_RGBA32F, cam.width, cam.height, GL_NEAREST, "translucent-eye");
        t.eyeFb = gl::createFramebuffer("translucent-eye");
        glNamedFramebufferTexture(t.eyeFb.id(), GL_COLOR_ATTACHMENT0, t.eye.id(), 0);
        gl::checkFramebufferComplete(t.eyeFb, "the translucent eye buffer's");
        t.width = cam.width, t.height = cam.height;
    }
    if (t.lightSide != side) {
        for (int k = 0; k < 2; ++k) {
            t.direct[k] = gl::createTexture2D(GL_RGBA32F, side, side, GL_LINEAR, "light-direct");
            t.indirect[k] = gl::createTexture2D(GL_RGBA32F, side, side, GL_LINEAR, "light-indirect");
            t.lightFb[k] = gl::createFramebuffer("translucent-light");
            glNamedFramebufferTexture(t.lightFb[k].id(), GL_COLOR_ATTACHMENT0, t.direct[k].id(), 0);
            glNamedFramebufferTexture(t.lightFb[k].id(), GL_COLOR_ATTACHMENT1, t.indirect[k].id(), 0);
            const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
            glNamedFramebufferDrawBuffers(t.lightFb[k].id(), 2, buffers);
            gl::checkFramebufferComplete(t.lightFb[k], "the translucent light buffer's");
        }
        t.lightSide = side;
    }
    {  // The phase table: texel i at cos θ = -1 + 2 i / (N - 1).
        std::vector<float> table(layout::kPhaseTableSize);
        for (int i = 0; i < layout::kPhaseTableSize; ++i)
            table[size_t(i)] = float(phaseOf(lighting.phase, -1.0 + 2.0 * i / (layout::kPhaseTableSize - 1)));
        glTextureSubImage2D(t.phase.id(), 0, 0, 0, layout::kPhaseTableSize, 1, GL_RED, GL_FLOAT, table.data());
    }

    // The light: the first directional light with any irradiance (none: emission only).
    DirectionalLight light{{0, 1, 0}, {0, 0, 0}};
    for (const auto& l : lighting.lights)
        if (std::max({l.irradiance.x, l.irradiance.y, l.irradiance.z}) > 0) {
            light = l;
            break;
        }
    const Vec3d towardLight = normalize(light.direction);
    const Vec3d travel = -towardLight, forward = normalize(cam.target - cam.eye);
    // The half-angle rule (Sec. 3.1): halfway between the light's travel and the view direction
    // when they agree (slices front to back for the eye), else the inverted view (back to front).
    const bool frontToBack = dot(travel, forward) >= 0;
    const Vec3d s = normalize(frontToBack ? travel + forward : travel - forward);

    const auto corners = boxCorners(volume);
    double tMin = 1e300, tMax = -1e300, far = 0, nearest = 1e300;
    for (const Vec3d& c : corners) {
        tMin = std::min(tMin, dot(c, s)), tMax = std::max(tMax, dot(c, s));
        far = std::max(far, length(c - cam.eye));
        nearest = std::min(nearest, dot(c - cam.eye, forward));
    }
    const Mat4& w = volume.worldFromIndex();
    const double voxelSize = std::cbrt(length(w.applyVector({1, 0, 0})) * length(w.applyVector({0, 1, 0})) * length(w.applyVector({0, 0, 1})));
    const double spacing = settings.sliceSpacing * voxelSize;
    const int slices = std::max(1, int(std::ceil((tMax - tMin) / spacing)));
    double depth0 = 1e300, depth1 = -1e300;  // the box's depth along the light's travel
    for (const Vec3d& c : corners) depth0 = std::min(depth0, dot(c, travel)), depth1 = std::max(depth1, dot(c, travel));
    const double tanHalf = std::tan(settings.indirect.blurAngleDeg * std::numbers::pi / 360);
    const double reach = settings.indirect.enabled ? std::min((depth1 - depth0) * tanHalf, depth1 - depth0) : 0;
    const LightFrame frame = lightFrame(corners, towardLight, side, reach);

    layout::TranslucentParams p;
    p.lightUvFromWorld = toGl(frame.uvFromWorld());
    p.indexFromWorld = toGl(volume.worldFromIndex().inverseAffine());
    p.dims = {volume.dims().x, volume.dims().y, volume.dims().z, side};
    p.sparseOffset = i4(volume.sparseOffset());
    p.eye = f4(cam.eye);
    p.sliceAxis = f4(s, spacing);
    p.lightDirection = f4(towardLight, spacing / dot(travel, s));
    p.irradiance = f4(light.irradiance);
    p.phase = {lighting.phase.type == PhaseType::HenyeyGreenstein ? 1.0f : 0.0f, float(lighting.phase.g), 0, 0};
    const IndirectLight& ind = settings.indirect;
    const double blur = spacing / dot(travel, s) * tanHalf;  // Eq. 9
    p.indirect = {ind.enabled ? 1.0f : 0.0f, float(blur / frame.extent), float(ind.extinction), float(settings.surfaceShading)};
    p.transport = f4(Vec3d(1 - std::log(ind.transportColor.x), 1 - std::log(ind.transportColor.y), 1 - std::log(ind.transportColor.z)));
    p.options = {volume.hasEmission() ? 1 : 0, volume.hasAlbedo() ? 1 : 0, 0, 0};
    const Perturbation& pert = settings.perturbation;
    if (pert.active()) {
        if (!t.hasNoise || t.noiseSeed != pert.seed) {
            const std::vector<float> texels = noiseTexels(pert.seed);
            t.noise = gl::createTexture(GL_TEXTURE_3D, "perturbation-noise");
            glTextureStorage3D(t.noise.id(), 1, GL_RGBA32F, kNoiseSize, kNoiseSize, kNoiseSize);
            glTextureSubImage3D(t.noise.id(), 0, 0, 0, 0, kNoiseSize, kNoiseSize, kNoiseSize, GL_RGBA, GL_FLOAT, texels.data());
            for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R}) glTextureParameteri(t.noise.id(), wrap, GL_REPEAT);
            glTextureParameteri(t.noise.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glTextureParameteri(t.noise.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            t.noiseSeed = pert.seed, t.hasNoise = true;
        }
        const PerturbationField field(pert, volume.dims());
        p.perturb = {float(pert.amplitude), float(pert.propertyAmplitude), float(field.texelsPerVoxel()), float(pert.octaves)};
        p.perturbTime = {float(pert.time), 0, 0, 0};
        glBindTextureUnit(layout::kUnitNoise, t.noise.id());
    }
    const Mat4 eyeClip = cameraClipFromWorld(cam, std::max(1e-4 * far, 0.99 * nearest), 1.01 * far + 1e-6);
    const Mat4 lightClip = frame.clipFromWorld();

    // Clear: nothing gathered by the eye; the light at full strength, direct and indirect.
    const float zero[4] = {0, 0, 0, 0}, one[4] = {1, 1, 1, 1};
    glClearNamedFramebufferfv(t.eyeFb.id(), GL_COLOR, 0, zero);
    for (int k = 0; k < 2; ++k) {
        glClearNamedFramebufferfv(t.lightFb[k].id(), GL_COLOR, 0, one);
        glClearNamedFramebufferfv(t.lightFb[k].id(), GL_COLOR, 1, one);
    }
    glBindTextureUnit(layout::kUnitExtinction, volume.extinctionTexture());
    if (volume.isSparse()) glBindTextureUnit(layout::kUnitBrickTable, volume.brickTableTexture());
    if (volume.hasAlbedo()) glBindTextureUnit(layout::kUnitAlbedo, volume.albedoTexture());
    if (volume.hasEmission()) glBindTextureUnit(layout::kUnitEmission, volume.emissionTexture());
    glBindTextureUnit(layout::kUnitPhaseTable, t.phase.id());
    glBindVertexArray(t.vao.id());
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    // A sparse volume's kernels read through its brick table (a dense volume's source is unchanged).
    auto variant = [&](const char* pass) {
        gl::ShaderBuilder b("translucent.raster");
        b.define(pass, 1);
        if (volume.isSparse()) b.define("VOLSTYLE_SPARSE", 1);
        return b;
    };
    const gl::Program& eyeProgram = m_device.program(variant("VOLSTYLE_PASS_EYE"));
    const gl::Program& lightProgram = m_device.program(variant("VOLSTYLE_PASS_LIGHT"));
    auto draw = [&](const std::vector<Vec3d>& polygon) {
        std::vector<float> xyz;
        for (const Vec3d& v : polygon) xyz.insert(xyz.end(), {float(v.x), float(v.y), float(v.z)});
        glNamedBufferSubData(t.vertices.id(), 0, GLsizeiptr(xyz.size() * sizeof(float)), xyz.data());
        glDrawArrays(GL_TRIANGLE_FAN, 0, GLsizei(polygon.size()));
    };

    // The budget (and a cancel) is checked every few slices: as many as fill about 4M texels, so
    // a 4096² render stops within a slice of its budget, not 16 slices (9 s) past it.
    const double sliceTexels = double(cam.width) * cam.height + 2.0 * settings.lightBufferSize * settings.lightBufferSize;
    const int checkEvery = std::clamp(int(4e6 / sliceTexels), 1, 16);
    int drawn = 0;
    for (int k = 0; k < slices; ++k) {
        if (budget.bounded() && k % checkEvery == 0) {
            glFinish();  // the time spent is the GPU's
            budget.check("the translucent slices", double(k) / slices);
        }
        const double tk = tMin + (k + 0.5) * spacing;
        const std::vector<Vec3d> polygon = slicePolygon(corners, s, tk);
        if (polygon.empty()) continue;
        const int cur = drawn % 2, next = 1 - cur;
        ++drawn;
        glBindTextureUnit(layout::kUnitLightDirect, t.direct[cur].id());
        glBindTextureUnit(layout::kUnitLightIndirect, t.indirect[cur].id());
        // 1. The eye's view of the slice, lit by the light so far (Fig. 3a).
        glBindFramebuffer(GL_FRAMEBUFFER, t.eyeFb.id());
        glViewport(0, 0, cam.width, cam.height);
        glEnable(GL_BLEND);
        glBlendEquation(GL_FUNC_ADD);
        if (frontToBack) glBlendFuncSeparate(GL_ONE_MINUS_DST_ALPHA, GL_ONE, GL_ONE_MINUS_DST_ALPHA, GL_ONE);  // under
        else glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);                                                   // over
        glUseProgram(eyeProgram.id());
        p.clipFromWorld = toGl(eyeClip);
        m_device.setParams(p);
        draw(polygon);
        // 2. The light's view: the next light buffers (Fig. 3b), every texel.
        glDisable(GL_BLEND);
        glBindFramebuffer(GL_FRAMEBUFFER, t.lightFb[next].id());
        glViewport(0, 0, side, side);
        glUseProgram(lightProgram.id());
        p.clipFromWorld = toGl(lightClip);
        m_device.setParams(p);
        draw(lightQuad(frame, s, tk));
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(0);

    // Read back (GL's rows run bottom-up) and put the background behind the medium.
    std::vector<float> pixels(size_t(cam.width) * cam.height * 4);
    glGetTextureImage(t.eye.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(pixels.size() * sizeof(float)), pixels.data());
    std::unique_ptr<LobeBasis> basis;
    std::vector<Vec3d> lobes;
    if (lighting.background.fromLobes && lighting.environment.active()) {
        basis = std::make_unique<LobeBasis>(lighting.environment.basis());
        lobes = lobeRadiance(lighting.environment);
    }
    Image out(cam.width, cam.height);
    if (medium) *medium = Image(cam.width, cam.height);
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const float* src = &pixels[(size_t(cam.height - 1 - y) * cam.width + x) * 4];
            float* dst = out.pixel(x, y);
            const Vec3d bg = backgroundAt(lighting, cam, x, y, lobes, basis.get());
            const double a = std::clamp(double(src[3]), 0.0, 1.0);
            for (int c = 0; c < 3; ++c) dst[c] = float(src[c] + (1 - a) * bg[c]);
            dst[3] = float(a);
            if (medium) std::copy(src, src + 4, medium->pixel(x, y));
        }
    if (statsOut) {
        statsOut->slices = drawn;
        statsOut->totalMs = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    }
    return out;
}

double TranslucentRenderer::estimatedTexels(Int3 dims, const Camera& camera, const TranslucentSettings& settings) {
    const double diagonal = std::sqrt(double(dims.x) * dims.x + double(dims.y) * dims.y + double(dims.z) * dims.z);
    const double slices = std::ceil(diagonal / std::max(settings.sliceSpacing, 1e-6));
    const double light = double(settings.lightBufferSize);
    return slices * (double(camera.width) * camera.height + 2 * light * light);  // direct and indirect light
}

}  // namespace volstyle::core
