#pragma once
/// \file tf_layers.h
/// Transfer-function layers (the Graphics Interface paper, Sec. 4.2; issue #15): a stack of solid,
/// gradient, image and diffusion layers blended bottom to top into the stylizer's TF texture F(V̄, d)
/// (x: V̄ from 0 at the left, y: d from 1 on row 0 to 0 on the last row, as stylize.comp reads it).
/// A diffusion layer spreads a few constraints over the square by a membrane (Laplace) solve, so one
/// constraint gives a uniform layer, two a gradient, more a smooth interpolation. GL-free.

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"

namespace volstyle::core {

/// Where a constraint clicked into the scene sits (issue #15): its TF position is recomputed for
/// each frame from the pixel this point projects to (core/stylize/tf_anchors.h).
struct TfAnchor {
    Vec3d position;      ///< world space, or the followed occluder's object space
    std::string follow;  ///< an occluder's name: the anchor moves with it; empty: fixed in the world
    bool operator==(const TfAnchor&) const = default;
};

/// A colour and alpha pinned at a point of the TF square: the texels of its bilinear footprint are
/// pinned, so the TF looked up at exactly (V̄, d) is the constraint's colour.
struct TfConstraint {
    double vBar = 0;   ///< [0, 1]
    double depth = 0;  ///< [0, 1]
    Vec3d colour{1, 1, 1};
    double alpha = 1;
    std::optional<TfAnchor> anchor = std::nullopt;  ///< set: (vBar, depth) follow the scene
    bool operator==(const TfConstraint&) const = default;
};

enum class TfLayerKind { Solid, Gradient, Image, Diffusion };
enum class TfBlend { Normal, Multiply, Add };

struct TfLayer {
    TfLayerKind kind = TfLayerKind::Solid;
    TfBlend blend = TfBlend::Normal;  ///< how it lies on the layers below, weighted by its alpha × opacity
    double opacity = 1;
    TfConstraint solid;                ///< Solid: its colour and alpha (the position is unused)
    TfConstraint from, to;             ///< Gradient: linear from `from` to `to` along their line, clamped
    std::shared_ptr<const Image> image;  ///< Image: stretched over the square (bilinear)
    std::vector<TfConstraint> constraints;  ///< Diffusion
    bool operator==(const TfLayer&) const = default;
};

struct TfCompileStats {
    int diffusionIterations = 0;  ///< CG iterations, all diffusion layers together
    double worstResidual = 0;     ///< the largest relative residual a diffusion solve stopped at
};

/// The layers blended bottom (first) to top onto a w×h RGBA image, starting transparent black.
/// Throws InvalidArgument on a bad size, an Image layer without an image or values outside [0, 1].
Image compileTfLayers(const std::vector<TfLayer>& layers, int width, int height, TfCompileStats* stats = nullptr);

/// F(V̄, d) as the stylizer's shader reads it (stylize.comp's transferFunction): bilinear between
/// texel centres, clamped, row 0 at d = 1. RGBA.
std::array<double, 4> sampleTransferFunction(const Image& tf, double vBar, double depth);

/// The membrane interpolation of `constraints` on a w×h grid of texel centres: each constraint fixes
/// the texels its bilinear lookup reads (several on one texel: their mean); every other texel is the mean of its
/// neighbours (Δu = 0, mirrored at the edges), solved by Jacobi-preconditioned CG in double to
/// `tolerance` relative residual. RGBA per texel; no constraint: transparent black.
std::vector<Vec3d> diffuseConstraints(const std::vector<TfConstraint>& constraints, int width, int height,
                                      std::vector<double>& alpha, int* iterations = nullptr, double* residual = nullptr,
                                      double tolerance = 1e-10);

}  // namespace volstyle::core
