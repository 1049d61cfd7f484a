#pragma once
/// \file keyframe_solver.h
/// Key frames of an animated volume solved jointly (issue #16, the TVCG paper's Sec.
/// "Animation", taken further): each key frame k has its own volume (its extinction) and views;
/// its emission or albedo a_k is solved for
///     Σ_k ‖W_k a_k − o_k‖²_D + regularization + λ_t Σ_{neighbours j,k} ‖a_k − A_{j→k} a_j‖²,
/// where A_{j→k} carries a_j to frame k: voxel for voxel (the paper's "same voxel over time"), or
/// along the sequence's velocity (`vel` grids; beyond the paper). The joint problem is solved by
/// block Gauss–Seidel: sweep 0 solves each frame alone, each later sweep re-solves frame k with
/// the prior ‖a_k − p_k‖², p_k the mean of its neighbours carried to it (equal, up to a
/// constant, to its share of the temporal term), warm-started from its last solution. A frame
/// without views takes p_k (its own least-squares answer). After each solve the frame's values are
/// extended into its empty voxels by diffusion (the paper's remedy), so a voxel that fills in a
/// later frame carries sensible values there. Frames between key frames are blended (inBetween).
/// GL thread only; GL-free header.

#include <functional>
#include <optional>
#include <vector>

#include "core/gpu/gpu_device.h"
#include "core/scene/solve_options.h"
#include "core/volume/sequence.h"
#include "core/volume/volume.h"

namespace volstyle::core {

struct KeyFrame {
    int frame = 0;                 ///< its frame number (increasing along the sequence)
    Volume volume;                 ///< its extinction; its emission/albedo is the start
    std::vector<SolveView> views;  ///< may be empty: the frame then follows its neighbours
    /// The velocity (world units per frame, 3 per voxel; a `vel` grid), or none.
    std::vector<float> velocity;
};

struct KeyFrameOptions {
    SolveOptions solve;        ///< emission or albedo; the per-frame options
    double temporal = 1;       ///< λ_t per hull unknown (as `l2`)
    int sweeps = 4;            ///< Gauss–Seidel sweeps over the frames (1: each frame alone)
    bool followFlow = true;    ///< carry values along the velocity where frames have one
    bool extendIntoEmpty = true;
};

struct KeyFrameReport {
    int sweeps = 0;
    /// Per sweep: the largest change of any frame's values (max abs), the last one's convergence.
    std::vector<double> change;
    std::vector<SolveReport> frames;  ///< the last solve of each frame (frames without views: empty)
    std::vector<std::vector<double>> startRms;  ///< per frame, its views' RMS before its first solve
    double solveSeconds = 0, extendSeconds = 0;  ///< wall clock in the frames' solves, and in extending them
};

/// Puts the frames of one sequence (one box and transform) on one brick layout when any of them is
/// sparse (issue #39): the union of their active bricks and of the apron a solve of `unknown`
/// adds to each (sparseSolveApron), so that a key frame's solve keeps the layout and values carry
/// from frame to frame brick for brick. Dense frames among sparse ones are stored sparse too;
/// each non-empty velocity grid (`velocities[i]`, may be null) follows its frame. Nothing changes
/// when every frame is dense. Throws InvalidArgument when the frames' boxes or brick offsets differ.
void putFramesOnOneLayout(const std::vector<Volume*>& frames, const std::vector<std::vector<float>*>& velocities, Unknown unknown);

/// The solved key frames' volumes, in the input's order. Throws InvalidArgument: fewer than one
/// frame, frames of different dims or transforms, sparse frames on different layouts
/// (putFramesOnOneLayout first), frame numbers not increasing, velocity grids of the wrong size,
/// an unknown other than emission or albedo, or invalid per-frame options.
std::vector<Volume> solveKeyFrames(GpuDevice& device, const std::vector<KeyFrame>& frames, const Lighting& lighting,
                                   const KeyFrameOptions& options, KeyFrameReport* report = nullptr,
                                   const std::function<void(int sweep, int frame)>& progress = {});

/// Frame f's property (emission or albedo, as `unknown`) from the solved key frames (`keys`
/// for their frame numbers and velocities, `solved` in the same order): a key frame's own values;
/// between two key frames their blend, each carried along its flow (with `followFlow`); before
/// the first or after the last, carried from it. On the solved volumes' layout (sparse: the frame
/// must share it, putFramesOnOneLayout).
std::vector<float> frameFromKeys(const std::vector<KeyFrame>& keys, const std::vector<Volume>& solved, Unknown unknown, int f,
                                 bool followFlow);

/// The property (`unknown`'s grid) of frame f between key frames a (frame fa) and b (frame fb):
/// each carried to f along its velocity (when given) and blended linearly by (f − fa)/(fb − fa).
std::vector<float> inBetween(const std::vector<float>& a, int fa, const std::vector<float>& velocityA, const std::vector<float>& b, int fb,
                             const std::vector<float>& velocityB, int f, const GridSpace& space, const Mat4& worldFromIndex);

}  // namespace volstyle::core
