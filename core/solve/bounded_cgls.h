#pragma once
/// \file bounded_cgls.h
/// Bounded CGLS (TVCG Sec. 5.1, SPEC §2), written once for the volume solver (its vectors on the
/// GPU, solver.cpp) and the light solver (lobes on the CPU, light_solver.cpp): min ‖A x − b‖²
/// over x in a box, three channels in lockstep, preconditioned by a column scaling M = D².
///
/// The algorithm lives here — the exact line minimum α = p·s / ‖A p‖², the step cut at the first
/// bound (or the projected step, kept per channel only where it lowers the objective), the free
/// set, conjugacy kept while p stays a clear descent direction, and restarts from scratch that
/// clear the recurrences' drift. A problem supplies the vector operations on its own storage.
/// Internal to core/solve.

#include "core/math/vec.h"

namespace volstyle::core {

/// The least-squares problem as bounded CGLS sees it. It owns the iterate x, the residual
/// r = b − A x, the gradient s = Aᵀ r (zero where a variable at a bound would leave the box), its
/// preconditioned z = M s and the direction p, and A p (q) once curvature() has made it.
class BoundedLeastSquares {
public:
    virtual ~BoundedLeastSquares() = default;
    /// r = b − A x from scratch, s and z from it, p = z. Returns γ = s·z.
    virtual Vec3d restart() = 0;
    /// s and z from the current r (after a step). Returns γ = s·z.
    virtual Vec3d gradient() = 0;
    /// q = A p. Returns ‖q‖² per channel (the line minimum's denominator).
    virtual Vec3d curvature() = 0;
    /// Per channel, the largest t with x + t p inside the bounds (1e300 where none is met).
    virtual Vec3d stepToBound() = 0;
    /// x += t p and r −= t q, per channel.
    virtual void move(const Vec3d& t) = 0;
    /// x' = clamp(x + α p) in every channel, r following; the change d = x' − x and A d are kept
    /// for undoProjected.
    virtual void moveProjected(const Vec3d& alpha) = 0;
    /// Takes the last moveProjected back in the channels where `undo` is 1 (0 elsewhere).
    virtual void undoProjected(const Vec3d& undo) = 0;
    /// x clamped into the bounds: rounding only, every move stays inside.
    virtual void clampToBounds() = 0;
    /// The objective per channel: ‖r‖² and any constant part.
    virtual Vec3d objective() = 0;
    /// p·s per channel.
    virtual Vec3d slope() = 0;
    /// p = z + β p; with `freeOnly`, then p's components that push a variable at its bound
    /// outward are dropped.
    virtual void conjugate(const Vec3d& beta, bool freeOnly) = 0;
    /// Keeps x before a step; restoreIterate() puts it back after a step that broke down.
    virtual void keepIterate() = 0;
    virtual void restoreIterate() = 0;
};

struct CglsSettings {
    bool enforceBounds = true;
    /// Where a bound cuts a step: try the projected step first (else: the cut step only).
    bool projected = true;
    /// The recurrences' residuals drift in float32: every this many iterations they are
    /// recomputed from the unknowns (a restart).
    int restartEvery = 25;
    /// A channel whose step a bound cut restarts from its gradient (its free set changed).
    bool restartAfterCut = false;
};

/// What one iteration did.
struct CglsStep {
    bool cutShort = false;  ///< a bound cut some channel's step short of its line minimum
    Vec3d objective;        ///< after the step
    bool finite = true;     ///< false: the step broke down; the iterate is the one before it
};

class BoundedCgls {
public:
    BoundedCgls(BoundedLeastSquares& problem, CglsSettings settings) : m_problem(problem), m_settings(settings) {}

    /// From scratch: the residual, gradient and first direction of the current iterate.
    void start();
    /// Whether the (free) gradient is zero in every channel: nothing more to do.
    bool zeroGradient() const { return m_gamma.x <= 0 && m_gamma.y <= 0 && m_gamma.z <= 0; }
    /// One step along p, then the next direction (iteration counts from 1, for the restarts).
    CglsStep iterate(int iteration);

private:
    /// Moves x along p; true when a bound cut some channel's step short.
    bool takeStep(const Vec3d& alpha, const Vec3d& toBound, const bool hit[3]);
    void nextDirection(int iteration, const bool cut[3]);

    BoundedLeastSquares& m_problem;
    CglsSettings m_settings;
    Vec3d m_gamma;  ///< s·z of the current gradient
    Vec3d m_slope;  ///< p·s: the objective's descent rate along p (= γ in plain CGLS)
};

}  // namespace volstyle::core
