#include "core/render/refracted_paths.h"

#include <fmt/format.h>

#include "core/base/errors.h"
#include "core/base/stopwatch.h"
#include "core/render/curved_paths.h"
#include "core/shaders/layout.h"

namespace volstyle::core {
namespace {

/// Everything a path depends on: the grid (content and placement), the camera's rays and the step.
std::string pathsKey(const RefractiveGrid& grid, const Camera& c, const RenderSettings& s) {
    return fmt::format("refracted-paths:{}:{},{},{}:{},{},{}:{},{},{}:{}:{}x{}:{},{}:{}", grid.hash(), c.eye.x, c.eye.y, c.eye.z, c.target.x,
                       c.target.y, c.target.z, c.up.x, c.up.y, c.up.z, c.fovYDeg, c.width, c.height, c.nearDist, c.farDist, s.stepVoxels);
}

}  // namespace

std::shared_ptr<const RefractedPaths> refractedPaths(GpuDevice& device, const GpuVolume& volume, const Camera& camera,
                                                     const RenderSettings& settings, RenderStats& stats, const WorkBudget& budget) {
    const auto& grid = volume.refraction();
    if (!grid || !settings.refraction) return nullptr;
    const std::string key = pathsKey(*grid, camera, settings);
    if (auto cached = device.cache().find<RefractedPaths>(key)) return cached;
    const auto t0 = Clock::now();
    PathTracing tracing;
    tracing.stepVoxels = settings.stepVoxels;
    const ViewPaths paths = traceViewPaths(*grid, camera, tracing, budget);
    auto gpu = std::make_shared<RefractedPaths>();
    gpu->start = gl::createBuffer(paths.start.size() * sizeof(uint32_t), paths.start.data(), 0, "path-start");
    gpu->vertices = gl::createBuffer(std::max<size_t>(paths.vertices.size(), 1) * sizeof(PathVertex),
                                     paths.vertices.empty() ? nullptr : paths.vertices.data(), 0, "path-vertices");
    gpu->exits = gl::createBuffer(paths.exitDirection.size() * 4 * sizeof(float), paths.exitDirection.data(), 0, "path-exits");
    if (glGetError() == GL_OUT_OF_MEMORY) throw OutOfMemory("out of GPU memory for the refracted rays' paths");
    gpu->vertexCount = paths.vertices.size();
    gpu->bytes = paths.bytes();
    gpu->traceMs = msSince(t0);
    stats.refractionMs += gpu->traceMs;
    return device.cache().insert<RefractedPaths>(key, std::move(gpu));
}

void bindRefractedPaths(const RefractedPaths& paths) {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingPathStart, paths.start.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingPathVertex, paths.vertices.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingPathExit, paths.exits.id());
}

}  // namespace volstyle::core
