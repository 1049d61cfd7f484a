#include "core/stylize/tf_layers.h"

#include <algorithm>
#include <functional>
#include <memory>
#include <cmath>
#include <string>

#include "core/base/errors.h"

namespace volstyle::core {
namespace {

bool unit(double x) { return x >= 0 && x <= 1; }

constexpr double kCompileTolerance = 1e-6;

void checkConstraint(const TfConstraint& c, const std::string& what) {
    if (!unit(c.vBar) || !unit(c.depth)) throw InvalidArgument(what + ": the position must be in [0, 1]²");
    if (!unit(c.colour.x) || !unit(c.colour.y) || !unit(c.colour.z) || !unit(c.alpha))
        throw InvalidArgument(what + ": colour and alpha must be in [0, 1]");
}

/// The texels a bilinear lookup at (V̄, d) reads with a nonzero weight (1, 2 or 4; x from V̄,
/// row 0 at d = 1), as stylize.comp's transferFunction() reads them.
std::vector<size_t> footprintOf(const TfConstraint& c, int w, int h) {
    const double fx = std::clamp(c.vBar * w - 0.5, 0.0, double(w - 1)), fy = std::clamp((1 - c.depth) * h - 0.5, 0.0, double(h - 1));
    const int x0 = int(fx), y0 = int(fy);
    const int x1 = fx > x0 ? std::min(x0 + 1, w - 1) : x0, y1 = fy > y0 ? std::min(y0 + 1, h - 1) : y0;
    std::vector<size_t> out;
    for (int y : {y0, y1})
        for (int x : {x0, x1}) {
            const size_t t = size_t(y) * size_t(w) + size_t(x);
            if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
        }
    return out;
}

/// Bilinear, clamped, between texel centres; (u, v) in [0, 1]² with v = 0 at the top row.
void sampleImage(const Image& img, double u, double v, double out[4]) {
    const double x = std::clamp(u * img.width - 0.5, 0.0, double(img.width - 1));
    const double y = std::clamp(v * img.height - 0.5, 0.0, double(img.height - 1));
    const int x0 = int(x), y0 = int(y), x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
    const double fx = x - x0, fy = y - y0;
    for (int c = 0; c < 4; ++c) {
        const double top = (1 - fx) * img.pixel(x0, y0)[c] + fx * img.pixel(x1, y0)[c];
        const double bottom = (1 - fx) * img.pixel(x0, y1)[c] + fx * img.pixel(x1, y1)[c];
        out[c] = (1 - fy) * top + fy * bottom;
    }
}

/// A multigrid V-cycle for the graph Laplacian over a grid's free texels (pinned ones eliminated),
/// as CG's preconditioner: forward Gauss–Seidel before the coarse correction and backward after it
/// (so the cycle is symmetric), coarse grids of half the side where a texel is pinned if any child
/// is, piecewise-constant prolongation and its transpose (the children's sum) as restriction.
class Multigrid {
public:
    Multigrid(int w, int h, const std::vector<char>& pinned) {
        m_levels.push_back(makeLevel(w, h, pinned));
        while (m_levels.back().w > 4 && m_levels.back().h > 4) {
            const Level& f = m_levels.back();
            const int cw = (f.w + 1) / 2, ch = (f.h + 1) / 2;
            std::vector<char> coarse(size_t(cw) * size_t(ch), 0);
            for (int y = 0; y < f.h; ++y)
                for (int x = 0; x < f.w; ++x)
                    if (f.pinned[size_t(y) * size_t(f.w) + size_t(x)]) coarse[size_t(y / 2) * size_t(cw) + size_t(x / 2)] = 1;
            m_levels.push_back(makeLevel(cw, ch, coarse));
        }
    }
    /// z ≈ A⁻¹ r, both over the finest grid's texels (pinned entries 0).
    void apply(const std::vector<double>& r, std::vector<double>& z) {
        m_levels[0].b = r;
        cycle(0);
        z = m_levels[0].x;
    }

private:
    struct Level {
        int w = 0, h = 0;
        std::vector<char> pinned;
        std::vector<double> diag, x, b, r;
    };
    static Level makeLevel(int w, int h, const std::vector<char>& pinned) {
        Level l{w, h, pinned, std::vector<double>(pinned.size(), 0.0), {}, {}, {}};
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) l.diag[size_t(y) * size_t(w) + size_t(x)] = (x > 0) + (x < w - 1) + (y > 0) + (y < h - 1);
        l.x.assign(pinned.size(), 0.0), l.b.assign(pinned.size(), 0.0), l.r.assign(pinned.size(), 0.0);
        return l;
    }
    /// Σ x over t's free neighbours.
    static double neighbourSum(const Level& l, int x, int y) {
        double s = 0;
        const size_t t = size_t(y) * size_t(l.w) + size_t(x);
        if (x > 0 && !l.pinned[t - 1]) s += l.x[t - 1];
        if (x < l.w - 1 && !l.pinned[t + 1]) s += l.x[t + 1];
        if (y > 0 && !l.pinned[t - size_t(l.w)]) s += l.x[t - size_t(l.w)];
        if (y < l.h - 1 && !l.pinned[t + size_t(l.w)]) s += l.x[t + size_t(l.w)];
        return s;
    }
    static void sweep(Level& l, bool forward) {
        const int n = l.w * l.h;
        for (int k = 0; k < n; ++k) {
            const int t = forward ? k : n - 1 - k;
            if (l.pinned[size_t(t)]) continue;
            l.x[size_t(t)] = (l.b[size_t(t)] + neighbourSum(l, t % l.w, t / l.w)) / l.diag[size_t(t)];
        }
    }
    void cycle(size_t level) {
        Level& l = m_levels[level];
        std::fill(l.x.begin(), l.x.end(), 0.0);
        if (level + 1 == m_levels.size()) {  // coarsest: sweep it to (near) convergence, symmetrically
            for (int i = 0; i < 30; ++i) sweep(l, true), sweep(l, false);
            return;
        }
        for (int i = 0; i < 2; ++i) sweep(l, true);
        Level& c = m_levels[level + 1];
        std::fill(c.b.begin(), c.b.end(), 0.0);
        for (int y = 0; y < l.h; ++y)
            for (int x = 0; x < l.w; ++x) {
                const size_t t = size_t(y) * size_t(l.w) + size_t(x);
                if (l.pinned[t]) continue;
                const double residual = l.b[t] - (l.diag[t] * l.x[t] - neighbourSum(l, x, y));
                const size_t parent = size_t(y / 2) * size_t(c.w) + size_t(x / 2);
                if (!c.pinned[parent]) c.b[parent] += residual;
            }
        cycle(level + 1);
        for (int y = 0; y < l.h; ++y)
            for (int x = 0; x < l.w; ++x) {
                const size_t t = size_t(y) * size_t(l.w) + size_t(x);
                if (!l.pinned[t]) l.x[t] += c.x[size_t(y / 2) * size_t(c.w) + size_t(x / 2)];
            }
        for (int i = 0; i < 2; ++i) sweep(l, false);
    }
    std::vector<Level> m_levels;
};

}  // namespace

std::array<double, 4> sampleTransferFunction(const Image& tf, double vBar, double depth) {
    std::array<double, 4> out{};
    sampleImage(tf, std::clamp(vBar, 0.0, 1.0), 1 - std::clamp(depth, 0.0, 1.0), out.data());
    return out;
}

namespace {

/// Preconditioned conjugate gradients on A x = b (A symmetric positive definite, given by
/// `apply`), from the start in `x`, to `tolerance` relative residual or `maxIterations`; the
/// iterations taken, and the relative residual reached in `relative`.
int preconditionedCg(const std::function<void(const std::vector<double>&, std::vector<double>&)>& apply,
                     const std::function<void(const std::vector<double>&, std::vector<double>&)>& precondition, const std::vector<double>& b,
                     std::vector<double>& x, double tolerance, int maxIterations, double& relative) {
    const size_t m = x.size();
    std::vector<double> r(m), z(m), p(m), q(m);
    apply(x, q);
    double bNorm = 0, rz = 0;
    for (size_t i = 0; i < m; ++i) r[i] = b[i] - q[i], bNorm += b[i] * b[i];
    precondition(r, z);
    for (size_t i = 0; i < m; ++i) p[i] = z[i], rz += r[i] * z[i];
    bNorm = std::max(std::sqrt(bNorm), 1e-300);
    double rNorm = 0;
    for (double v : r) rNorm += v * v;
    rNorm = std::sqrt(rNorm);
    int it = 0;
    while (rNorm > tolerance * bNorm && it < maxIterations) {
        apply(p, q);
        double pq = 0;
        for (size_t i = 0; i < m; ++i) pq += p[i] * q[i];
        if (pq <= 0) break;
        const double a = rz / pq;
        double rzNew = 0;
        rNorm = 0;
        for (size_t i = 0; i < m; ++i) {
            x[i] += a * p[i];
            r[i] -= a * q[i];
            rNorm += r[i] * r[i];
        }
        precondition(r, z);
        for (size_t i = 0; i < m; ++i) rzNew += r[i] * z[i];
        rNorm = std::sqrt(rNorm);
        const double beta = rzNew / rz;
        rz = rzNew;
        for (size_t i = 0; i < m; ++i) p[i] = z[i] + beta * p[i];
        ++it;
    }
    relative = rNorm / bNorm;
    return it;
}

}  // namespace

std::vector<Vec3d> diffuseConstraints(const std::vector<TfConstraint>& constraints, int w, int h, std::vector<double>& alpha,
                                      int* iterations, double* residual, double tolerance) {
    const size_t n = size_t(w) * h;
    std::vector<Vec3d> colour(n);
    alpha.assign(n, 0.0);
    if (iterations) *iterations = 0;
    if (residual) *residual = 0;
    if (constraints.empty()) return colour;
    // The pinned texels: the mean of the constraints on each.
    std::vector<double> pinned[4];
    std::vector<int> count(n, 0);
    for (auto& p : pinned) p.assign(n, 0.0);
    for (const TfConstraint& c : constraints)
        for (size_t t : footprintOf(c, w, h)) {
            ++count[t];
            const double v[4] = {c.colour.x, c.colour.y, c.colour.z, c.alpha};
            for (int ch = 0; ch < 4; ++ch) pinned[ch][t] += v[ch];
        }
    std::vector<int> freeIndex(n, -1);
    std::vector<size_t> freeTexels;
    for (size_t t = 0; t < n; ++t) {
        if (count[t]) {
            for (auto& p : pinned) p[t] /= count[t];
        } else {
            freeIndex[t] = int(freeTexels.size());
            freeTexels.push_back(t);
        }
    }
    const size_t m = freeTexels.size();
    // Neighbours of each free texel inside the grid (mirrored edges: the missing ones drop out).
    auto neighbours = [&](size_t t, auto&& visit) {
        const int x = int(t % size_t(w)), y = int(t / size_t(w));
        if (x > 0) visit(t - 1);
        if (x < w - 1) visit(t + 1);
        if (y > 0) visit(t - size_t(w));
        if (y < h - 1) visit(t + size_t(w));
    };
    std::vector<double> diag(m, 0.0);
    for (size_t i = 0; i < m; ++i) neighbours(freeTexels[i], [&](size_t) { diag[i] += 1; });
    auto apply = [&](const std::vector<double>& x, std::vector<double>& y) {  // y = A x over the free texels
        for (size_t i = 0; i < m; ++i) {
            double s = diag[i] * x[i];
            neighbours(freeTexels[i], [&](size_t j) {
                if (freeIndex[j] >= 0) s -= x[size_t(freeIndex[j])];
            });
            y[i] = s;
        }
    };
    // Preconditioner: a multigrid V-cycle on grids big enough for it (CG alone needs iterations in
    // proportion to the side), else Jacobi.
    std::unique_ptr<Multigrid> mg;
    std::vector<double> gridR, gridZ;
    if (w >= 16 && h >= 16) {
        std::vector<char> pinnedMask(n, 0);
        for (size_t t = 0; t < n; ++t) pinnedMask[t] = count[t] ? 1 : 0;
        mg = std::make_unique<Multigrid>(w, h, pinnedMask);
        gridR.assign(n, 0.0);
    }
    auto precondition = [&](const std::vector<double>& r, std::vector<double>& z) {
        if (!mg) {
            for (size_t i = 0; i < m; ++i) z[i] = r[i] / diag[i];
            return;
        }
        for (size_t i = 0; i < m; ++i) gridR[freeTexels[i]] = r[i];
        mg->apply(gridR, gridZ);
        for (size_t i = 0; i < m; ++i) z[i] = gridZ[freeTexels[i]];
    };
    std::vector<double> result[4];
    for (int ch = 0; ch < 4; ++ch) {
        std::vector<double> b(m, 0.0), x(m);
        double mean = 0;
        for (const TfConstraint& c : constraints) mean += (ch == 0 ? c.colour.x : ch == 1 ? c.colour.y : ch == 2 ? c.colour.z : c.alpha);
        mean /= double(constraints.size());
        for (size_t i = 0; i < m; ++i) {
            neighbours(freeTexels[i], [&](size_t j) {
                if (freeIndex[j] < 0) b[i] += pinned[ch][j];
            });
            x[i] = mean;  // one constraint: already the answer
        }
        const int maxIterations = int(std::min<size_t>(20 * (size_t(w) + size_t(h)) + 100, 4 * m + 10));
        double relative = 0;
        const int it = preconditionedCg(apply, precondition, b, x, tolerance, maxIterations, relative);
        if (iterations) *iterations += it;
        if (residual) *residual = std::max(*residual, relative);
        result[ch].assign(n, 0.0);
        for (size_t t = 0; t < n; ++t) result[ch][t] = freeIndex[t] >= 0 ? x[size_t(freeIndex[t])] : pinned[ch][t];
    }
    for (size_t t = 0; t < n; ++t) {
        colour[t] = Vec3d(result[0][t], result[1][t], result[2][t]);
        alpha[t] = result[3][t];
    }
    return colour;
}

Image compileTfLayers(const std::vector<TfLayer>& layers, int w, int h, TfCompileStats* stats) {
    if (w < 1 || h < 1 || w > 4096 || h > 4096) throw InvalidArgument("a transfer function is 1–4096 texels a side");
    if (stats) *stats = {};
    const size_t n = size_t(w) * h;
    std::vector<Vec3d> c(n);
    std::vector<double> a(n, 0.0);
    for (size_t k = 0; k < layers.size(); ++k) {
        const TfLayer& L = layers[k];
        const std::string what = "layer " + std::to_string(k);
        if (!unit(L.opacity)) throw InvalidArgument(what + ": opacity must be in [0, 1]");
        std::vector<Vec3d> lc(n);
        std::vector<double> la(n, 0.0);
        switch (L.kind) {
            case TfLayerKind::Solid:
                checkConstraint(L.solid, what);
                std::fill(lc.begin(), lc.end(), L.solid.colour);
                std::fill(la.begin(), la.end(), L.solid.alpha);
                break;
            case TfLayerKind::Gradient: {
                checkConstraint(L.from, what + " (from)");
                checkConstraint(L.to, what + " (to)");
                const double dx = L.to.vBar - L.from.vBar, dy = L.to.depth - L.from.depth, len2 = dx * dx + dy * dy;
                for (int y = 0; y < h; ++y)
                    for (int x = 0; x < w; ++x) {
                        const double v = (x + 0.5) / w, d = 1 - (y + 0.5) / h;
                        const double t = len2 > 0 ? std::clamp(((v - L.from.vBar) * dx + (d - L.from.depth) * dy) / len2, 0.0, 1.0) : 0.0;
                        const size_t i = size_t(y) * w + size_t(x);
                        lc[i] = L.from.colour * (1 - t) + L.to.colour * t;
                        la[i] = L.from.alpha * (1 - t) + L.to.alpha * t;
                    }
                break;
            }
            case TfLayerKind::Image:
                if (!L.image || L.image->empty()) throw InvalidArgument(what + ": an image layer needs its image");
                for (int y = 0; y < h; ++y)
                    for (int x = 0; x < w; ++x) {
                        double s[4];
                        sampleImage(*L.image, (x + 0.5) / w, (y + 0.5) / h, s);
                        const size_t i = size_t(y) * w + size_t(x);
                        lc[i] = Vec3d(s[0], s[1], s[2]);
                        la[i] = std::clamp(s[3], 0.0, 1.0);
                    }
                break;
            case TfLayerKind::Diffusion: {
                for (size_t i = 0; i < L.constraints.size(); ++i) checkConstraint(L.constraints[i], what + " constraint " + std::to_string(i));
                int it = 0;
                double res = 0;
                // 1e-6 of the residual: far below what an 8-bit or half-float TF can show.
                lc = diffuseConstraints(L.constraints, w, h, la, &it, &res, kCompileTolerance);
                if (stats) stats->diffusionIterations += it, stats->worstResidual = std::max(stats->worstResidual, res);
                break;
            }
        }
        // Blend onto what is below, weighted by the layer's alpha and opacity (the paper's alpha
        // guides how stacked layers mix).
        for (size_t i = 0; i < n; ++i) {
            const double w8 = std::clamp(la[i], 0.0, 1.0) * L.opacity;
            switch (L.blend) {
                case TfBlend::Normal:
                    c[i] = lc[i] * w8 + c[i] * (1 - w8);
                    a[i] = w8 + a[i] * (1 - w8);
                    break;
                case TfBlend::Multiply:
                    c[i] = Vec3d(c[i].x * (1 - w8 + w8 * lc[i].x), c[i].y * (1 - w8 + w8 * lc[i].y), c[i].z * (1 - w8 + w8 * lc[i].z));
                    break;
                case TfBlend::Add:
                    c[i] = c[i] + lc[i] * w8;
                    a[i] = std::min(1.0, a[i] + w8);
                    break;
            }
        }
    }
    // The blend keeps colour premultiplied by alpha; the TF stores it straight (as a PNG does, and
    // as `replace` reads it: F.rgb·F.a).
    Image out(w, h);
    for (size_t i = 0; i < n; ++i) {
        float* p = &out.rgba[4 * i];
        const Vec3d straight = a[i] > 0 ? c[i] / a[i] : c[i];
        p[0] = float(straight.x), p[1] = float(straight.y), p[2] = float(straight.z), p[3] = float(a[i]);
    }
    return out;
}

}  // namespace volstyle::core
