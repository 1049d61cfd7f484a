#pragma once
/// \file tf_anchors.h
/// Transfer functions built from layers (issue #15): compiling the stack into the TF image, the
/// constraints clicked into the scene (a pixel's V̄ and linear depth, found again for each frame
/// where the anchored point projects), and the TF applied on the CPU to a frame rendered without
/// it, exactly as stylize.comp applies it. GL-free.

#include <optional>

#include "core/stylize/scene.h"
#include "core/stylize/stylizer.h"

namespace volstyle::core {

/// The TF's position of a pixel: its V̄ and d = (s − near)/(far − near), clamped to [0, 1].
struct TfPosition {
    double vBar = 0, depth = 0;
};
TfPosition tfPositionAt(const TransferFunction& tf, const StylizedFrame& frame, int x, int y);

/// Where an anchor is in the world now (its occluder's transform applied when it follows one).
Vec3d anchorWorldPosition(const StylizerScene& scene, const TfAnchor& anchor);

/// An anchor for the surface point seen through pixel (x, y) at distance s: in the object space of
/// occluder `occluder` (≥ 0, followed) or in the world (−1).
TfAnchor anchorAtPixel(const StylizerScene& scene, int x, int y, double s, int occluder);

/// Moves every anchored constraint of `tf` to the TF position of the pixel its anchor projects to
/// in `frame` (rendered from `scene`'s camera); an anchor behind the camera or outside the image
/// keeps its last position. Returns how many moved.
int resolveAnchors(TransferFunction& tf, const StylizerScene& scene, const StylizedFrame& frame);

/// Compiles `tf.layers` into `tf.image` (nothing to do without layers).
void compileTransferFunction(TransferFunction& tf, TfCompileStats* stats = nullptr);

/// The frame with `tf` applied to a frame rendered without a TF: the scattering replaced by
/// F.rgb ⊙ L_scat (multiply) or F.rgb·F.a (replace), as stylize.comp does.
void applyTransferFunction(const TransferFunction& tf, StylizedFrame& frame);

}  // namespace volstyle::core
