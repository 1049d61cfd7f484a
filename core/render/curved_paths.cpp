#include "core/render/curved_paths.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <string_view>
#include <thread>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

constexpr int kBrick = 8;  // voxels a flat-brick side

/// [tEnter, tExit] of o + t d (index space) against the box [lo, hi].
std::pair<double, double> rayBox(const Vec3d& o, const Vec3d& d, const Vec3d& lo, const Vec3d& hi) {
    double a = -std::numeric_limits<double>::max(), b = std::numeric_limits<double>::max();
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) {
            if (o[k] < lo[k] || o[k] > hi[k]) return {1, 0};
            continue;
        }
        const double t0 = (lo[k] - o[k]) / d[k], t1 = (hi[k] - o[k]) / d[k];
        a = std::max(a, std::min(t0, t1)), b = std::min(b, std::max(t0, t1));
    }
    return {a, b};
}

size_t combine(size_t seed, size_t v) { return seed ^ (v + 0x9e3779b97f4a7c15ull + (seed << 6) + (seed >> 2)); }

}  // namespace

std::shared_ptr<const RefractiveGrid> RefractiveGrid::of(const Volume& volume) {
    const auto& n = volume.refractiveIndex();
    if (!n || n->empty()) return nullptr;
    const auto [lo, hi] = std::minmax_element(n->begin(), n->end());
    if (*lo == *hi) return nullptr;  // constant: no gradient anywhere, the rays stay straight
    return std::shared_ptr<const RefractiveGrid>(new RefractiveGrid(volume));
}

RefractiveGrid::RefractiveGrid(const Volume& volume)
    : m_values(std::make_shared<const std::vector<float>>(*volume.refractiveIndex())),
      m_layout(volume.bricks() ? std::make_shared<const BrickLayout>(*volume.bricks()) : nullptr),
      m_dims(volume.dims()),
      m_worldFromIndex(volume.worldFromIndex()),
      m_indexFromWorld(volume.worldFromIndex().inverseAffine()),
      m_field(indexFieldOf(m_values, m_dims, m_worldFromIndex, m_layout)) {
    const std::vector<float>& g = *m_values;
    m_hash = std::hash<std::string_view>()(std::string_view(reinterpret_cast<const char*>(g.data()), g.size() * sizeof(float)));
    for (int k = 0; k < 16; ++k) m_hash = combine(m_hash, std::hash<double>()(m_worldFromIndex.m[size_t(k)]));
    m_hash = combine(m_hash, size_t(m_dims.x) * 73856093u ^ size_t(m_dims.y) * 19349663u ^ size_t(m_dims.z) * 83492791u);
    if (m_layout) {  // where the stored values lie
        const Int3 o = m_layout->offset();
        m_hash = combine(m_hash, size_t(o.x) * 73856093u ^ size_t(o.y) * 19349663u ^ size_t(o.z) * 83492791u);
        m_layout->forEachActiveBrick([&](Int3 b, uint32_t slot) { m_hash = combine(m_hash, m_layout->brickIndex(b) * 2654435761u ^ slot); });
    }
    auto at = [&](int i, int j, int k) {
        return g[m_layout ? m_layout->storageIndex({i, j, k}) : (size_t(k) * m_dims.y + j) * m_dims.x + i];
    };
    // Whether a sparse volume's voxels [lo, hi] all lie in inactive bricks (all the background).
    auto allBackground = [&](Int3 lo, Int3 hi) {
        if (!m_layout) return false;
        const Int3 bLo = m_layout->brickOf(lo), bHi = m_layout->brickOf(hi);
        for (int z = bLo.z; z <= bHi.z; ++z)
            for (int y = bLo.y; y <= bHi.y; ++y)
                for (int x = bLo.x; x <= bHi.x; ++x)
                    if (m_layout->isActive({x, y, z})) return false;
        return true;
    };

    // A brick is flat when its voxels and their one-voxel apron (the corners a trilinear lookup
    // inside the brick can reach) hold one value.
    m_bricks = {(m_dims.x + kBrick - 1) / kBrick, (m_dims.y + kBrick - 1) / kBrick, (m_dims.z + kBrick - 1) / kBrick};
    m_flat.assign(size_t(m_bricks.volume()), 1);
    for (int bz = 0; bz < m_bricks.z; ++bz)
        for (int by = 0; by < m_bricks.y; ++by)
            for (int bx = 0; bx < m_bricks.x; ++bx) {
                const Int3 lo{std::max(bx * kBrick - 1, 0), std::max(by * kBrick - 1, 0), std::max(bz * kBrick - 1, 0)};
                const Int3 hi{std::min(bx * kBrick + kBrick, m_dims.x - 1), std::min(by * kBrick + kBrick, m_dims.y - 1),
                              std::min(bz * kBrick + kBrick, m_dims.z - 1)};
                if (allBackground(lo, hi)) continue;
                const float first = at(lo.x, lo.y, lo.z);
                bool flat = true;
                for (int k = lo.z; k <= hi.z && flat; ++k)
                    for (int j = lo.y; j <= hi.y && flat; ++j)
                        for (int i = lo.x; i <= hi.x; ++i)
                            if (at(i, j, k) != first) {
                                flat = false;
                                break;
                            }
                m_flat[(size_t(bz) * m_bricks.y + by) * m_bricks.x + bx] = flat ? 1 : 0;
            }
}

int RefractiveGrid::brickOf(const Vec3d& p, Int3* brick) const {
    auto axis = [&](int a) { return std::clamp(int(std::floor((p[a] + 0.5) / kBrick)), 0, m_bricks[a] - 1); };
    const Int3 b{axis(0), axis(1), axis(2)};
    if (brick) *brick = b;
    return m_flat[(size_t(b.z) * m_bricks.y + b.y) * m_bricks.x + b.x];
}

bool RefractiveGrid::flatAt(const Vec3d& p) const { return brickOf(p, nullptr) != 0; }

std::vector<PathVertex> traceViewPath(const RefractiveGrid& grid, const Vec3d& eye, const Vec3d& direction, double nearDist,
                                      double farDist, const PathTracing& tracing, Vec3d* exitDirection) {
    const Mat4& indexFromWorld = grid.indexFromWorld();
    const Int3 n = grid.dims();
    const Vec3d boxLo(-0.5, -0.5, -0.5), boxHi(n.x - 0.5, n.y - 0.5, n.z - 0.5);
    const Vec3d dir = normalize(direction);
    if (exitDirection) *exitDirection = dir;
    const auto [tIn, tOut] = rayBox(indexFromWorld.applyPoint(eye), indexFromWorld.applyVector(dir), boxLo, boxHi);
    const double start = std::max(tIn, 0.0);
    if (!(tOut > start) || start >= farDist) return {};
    (void)nearDist;  // the march clips the pieces to [near, far]; the path starts where the box does

    const Vec3d side = grid.worldFromIndex().applyVector({1, 0, 0}), up = grid.worldFromIndex().applyVector({0, 1, 0}),
                depth = grid.worldFromIndex().applyVector({0, 0, 1});
    const double h = tracing.stepVoxels * std::min({length(side), length(up), length(depth)});
    const double diagonal = length(grid.worldFromIndex().applyVector(Vec3d(n.x, n.y, n.z)));
    const int maxSteps = int(std::min(8.0 * diagonal / h + 1000, 1e6));  // a ray trapped inside gives up here

    std::vector<PathVertex> path;
    std::vector<Vec3d> world;  // the vertices in world space (for merging)
    auto push = [&](const Vec3d& x, double t) {
        // Three collinear vertices: the middle one is dropped (straight runs are one piece).
        if (world.size() >= 2) {
            const Vec3d a = world[world.size() - 2], b = world.back();
            const Vec3d u = b - a, w = x - b;
            if (length(cross(u, w)) <= 1e-10 * length(u) * length(w) && dot(u, w) > 0) {
                world.back() = x;
                const Vec3d p = indexFromWorld.applyPoint(x);
                path.back() = {float(p.x), float(p.y), float(p.z), float(path[path.size() - 2].t + length(x - a))};
                return;
            }
        }
        world.push_back(x);
        const Vec3d p = indexFromWorld.applyPoint(x);
        path.push_back({float(p.x), float(p.y), float(p.z), float(t)});
    };
    auto inside = [&](const Vec3d& p) {
        for (int a = 0; a < 3; ++a)
            if (!(p[a] >= boxLo[a] && p[a] <= boxHi[a])) return false;
        return true;
    };

    RayState s{eye + dir * start, dir * grid.field().n(eye + dir * start)};
    double t = start;  // the polyline's length from the eye: the march's t
    push(s.x, t);
    for (int step = 0; step < maxSteps && t < farDist; ++step) {
        const Vec3d p = indexFromWorld.applyPoint(s.x);
        RayState next;
        Int3 brick;
        double leave = 0;
        if (grid.brickOf(p, &brick)) {
            // ∇n = 0 in this brick: straight on to where the ray leaves it (v unchanged). On a
            // brick's face, heading out of it, that is nowhere: then an ordinary step.
            const Vec3d lo = Vec3d(brick.x, brick.y, brick.z) * double(kBrick) - Vec3d(0.5, 0.5, 0.5);
            leave = rayBox(p, indexFromWorld.applyVector(normalize(s.v)), lo, lo + Vec3d(kBrick, kBrick, kBrick)).second;
        }
        if (leave > 1e-3 * h)
            next = {s.x + normalize(s.v) * (leave + 1e-6 * h), s.v};
        else
            next = stepRay(grid.field(), s, h, tracing.scheme);
        const Vec3d q = indexFromWorld.applyPoint(next.x);
        if (!inside(q)) {
            // Cut the last piece where it leaves the box; straight from there on.
            const double leave = std::clamp(rayBox(p, q - p, boxLo, boxHi).second, 0.0, 1.0);
            const Vec3d x = s.x + (next.x - s.x) * leave;
            push(x, t + length(x - s.x));
            s = next;  // the step's end state: its direction is where the ray goes on (n = 1 at the box's faces)
            break;
        }
        t += length(next.x - s.x);
        s = next;
        push(s.x, t);
    }
    if (path.size() < 2) return {};
    if (exitDirection) *exitDirection = normalize(s.v);
    return path;
}

ViewPaths traceViewPaths(const RefractiveGrid& grid, const Camera& camera, const PathTracing& tracing, const WorkBudget& budget) {
    camera.validate();
    if (!(tracing.stepVoxels > 0) || !std::isfinite(tracing.stepVoxels))
        throw InvalidArgument("the refraction step must be a positive number of voxels");
    const int w = camera.width, h = camera.height;
    std::vector<std::vector<PathVertex>> rows(static_cast<size_t>(h));
    std::vector<std::vector<uint32_t>> counts(static_cast<size_t>(h), std::vector<uint32_t>(static_cast<size_t>(w)));
    std::vector<std::array<float, 4>> exits(size_t(w) * size_t(h));
    std::atomic<int> nextRow{0};
    std::atomic<size_t> bytes{0};
    std::atomic<bool> stop{false};
    std::exception_ptr failure;
    std::mutex failureLock;
    auto worker = [&] {
        try {
            for (int y = nextRow++; y < h && !stop; y = nextRow++) {
                budget.check("tracing the refracted rays", double(y) / h);
                for (int x = 0; x < w; ++x) {
                    Vec3d exit;
                    const auto path = traceViewPath(grid, camera.eye, camera.rayDirection(x, y), camera.nearDist, camera.farDist, tracing, &exit);
                    counts[size_t(y)][size_t(x)] = uint32_t(path.size());
                    exits[size_t(y) * size_t(w) + size_t(x)] = {float(exit.x), float(exit.y), float(exit.z), path.empty() ? 0.0f : 1.0f};
                    rows[size_t(y)].insert(rows[size_t(y)].end(), path.begin(), path.end());
                }
                if ((bytes += rows[size_t(y)].size() * sizeof(PathVertex)) > tracing.maxBytes)
                    throw OverBudget("the refracted rays of a " + std::to_string(w) + "x" + std::to_string(h) + " view need over " +
                                     std::to_string(tracing.maxBytes >> 20) + " MiB of path vertices: use a larger step or a smaller image");
            }
        } catch (...) {
            std::lock_guard<std::mutex> lock(failureLock);
            if (!failure) failure = std::current_exception();
            stop = true;
        }
    };
    std::vector<std::thread> threads;
    const unsigned extra = std::max(1u, std::thread::hardware_concurrency()) - 1;
    for (unsigned i = 0; i < extra; ++i) threads.emplace_back(worker);
    worker();
    for (auto& t : threads) t.join();
    if (failure) std::rethrow_exception(failure);

    ViewPaths paths;
    paths.width = w, paths.height = h;
    paths.start.reserve(size_t(w) * h + 1);
    size_t total = 0;
    for (const auto& r : rows) total += r.size();
    paths.vertices.reserve(total);
    uint32_t offset = 0;
    for (int y = 0; y < h; ++y) {
        for (uint32_t c : counts[size_t(y)]) {
            paths.start.push_back(offset);
            offset += c;
        }
        paths.vertices.insert(paths.vertices.end(), rows[size_t(y)].begin(), rows[size_t(y)].end());
        std::vector<PathVertex>().swap(rows[size_t(y)]);
    }
    paths.start.push_back(uint32_t(paths.vertices.size()));
    paths.exitDirection = std::move(exits);
    return paths;
}

}  // namespace volstyle::core
