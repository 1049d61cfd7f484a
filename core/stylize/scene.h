#pragma once
/// \file scene.h
/// The light-shaft stylizer's scene (SPEC §7, the GI paper Sec. 3): occluder meshes with a
/// transform and a colour each, one light (directional or spot), a homogeneous medium and the
/// camera, the occluders' manipulations and the transfer function. GL-free.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/volume/volume.h"

#include "core/math/vec.h"
#include "core/scene/camera.h"
#include "core/scene/lighting.h"
#include "core/scene/render_settings.h"
#include "core/stylize/mesh.h"
#include "core/stylize/tf_layers.h"

namespace volstyle::core {

/// Structuring elements of the shadow-map closing (core/stylize/morphology.h).
enum class MorphShape { Box, Disc };

/// How an occluder's shadow is edited for the scattering only (the GI paper Sec. 4); its surface
/// and the surfaces it shadows keep the unmodified map.
/// Applied in this order to the object's own shadow map, which is then folded into the
/// scattering's by minimum: closing, epipolar dilation (+ erosion), holes.
struct Manipulation {
    int closingRadius = 0;                  ///< texels of the shadow map; 0: no closing
    MorphShape closingShape = MorphShape::Disc;
    double dilationLength = 0;              ///< Eq. 3's kernel, world units across the beams; 0: none
    int erosionPx = 0;                      ///< box erosion after the dilation, texels
    double holeFrequency = 0.3;             ///< noise cycles per world unit across the beams
    double holeProbability = 0;             ///< share of the object's shadow turned into holes; 0: none
    uint32_t holeSeed = 1;
    double holeSpeed = 0;                   ///< noise units per unit of scene time
    int holeOctaves = 5;                    ///< Eq. 5 (the paper's Fig. 5 setting)
    double holePersistence = 0.5;
    bool any() const { return closingRadius > 0 || dilationLength > 0 || holeProbability > 0; }
    /// Every value out of its range below, with its JSON field ("closing/radius_px",
    /// "holes/octaves", …): the one place these ranges are checked (the API parser, the scene's
    /// validate() and the schema test read them from here).
    std::vector<FieldProblem> check() const;
    bool operator==(const Manipulation&) const = default;
};

/// The ranges of a Manipulation (SPEC §7 `manipulation`; the schema states the same, checked by
/// tests/unit/schema_limits_test.cpp).
inline constexpr int kMaxClosingRadiusPx = 64;   ///< texels of the shadow map
inline constexpr int kMaxErosionPx = 64;
inline constexpr double kMaxDilationLength = 1e6;  ///< world units
inline constexpr double kMaxHoleFrequency = 1e6;   ///< cycles per world unit
inline constexpr double kMaxHoleSpeed = 1e6;       ///< noise units per unit of scene time, either sign
inline constexpr int kMinHoleOctaves = 1, kMaxHoleOctaves = 8;

struct Occluder {
    std::string name;
    /// Shared and immutable: a scene is copied per frame and per edit (the server keeps uploads
    /// once), and the stylizer keeps each mesh's GPU copy while the mesh lives.
    std::shared_ptr<const Mesh> mesh;
    Mat4 worldFromObject;
    Vec3d colour{0.4, 0.35, 0.3};  ///< diffuse albedo of its surface
    Manipulation manipulation;
    bool operator==(const Occluder&) const = default;
};

enum class StylizerLightType { Directional, Spot };

struct StylizerLight {
    StylizerLightType type = StylizerLightType::Directional;
    Vec3d direction{0.3, 1.0, 0.2};  ///< directional: from the scene toward the light (SPEC §1)
    Vec3d position{0, 10, 0};        ///< spot: where it stands; it shines along -direction
    double coneDeg = 30;             ///< spot: full cone angle
    Vec3d irradiance{3, 2.9, 2.6};   ///< E (directional) or intensity (spot), RGB
    int shadowMapSize = 2048;        ///< 512–4096
    /// Every value out of its range, with its JSON field ("shadow_map_size", …): the one check
    /// (the API parser and StylizerScene::validate report it).
    std::vector<FieldProblem> check() const;
    bool operator==(const StylizerLight&) const = default;
};

struct HomogeneousMedium {
    double extinction = 0.05;  ///< σt per world unit
    double albedo = 0.9;       ///< ρ
    Phase phase{PhaseType::HenyeyGreenstein, 0.4};
    std::vector<FieldProblem> check() const;  ///< "extinction" in [0, 1e6], "albedo" in [0, 1]
    bool operator==(const HomogeneousMedium&) const = default;
};

/// A heterogeneous medium in place of the homogeneous one (issue #15, beyond the paper): σt =
/// extinctionScale × the mean of a volume's RGB extinction, the volume's voxels stretched over the
/// box [lo, hi] (nothing outside it). The volume itself is not part of the scene: whoever renders
/// passes it (Stylizer::render; the server passes the session's volume on the GPU), with the medium's albedo and phase. V̄ becomes the σt-weighted average,
/// along the view ray inside the box, of the visibility times the volume's transmittance toward
/// the light, and the first integral ∫σt e^{−τ(t)} dt is marched through the grid
/// (docs/STYLIZER.md "Heterogeneous media").
struct StylizerVolume {
    Vec3d lo{-1, -1, -1}, hi{1, 1, 1};
    double extinctionScale = 1;
    bool lightTransmittance = true;  ///< off: the medium does not dim the light (as the homogeneous model)
    int steps = 128;                 ///< samples along a view ray's part in the box, 1–4096
    /// A sparse volume (issue #39) is averaged over blocks of voxels until its medium grid has at
    /// most this many voxels (a dense volume is used voxel for voxel). Not in the API: a bound on
    /// the stylizer's memory and light pass (docs/STYLIZER.md).
    int64_t maxSparseMediumVoxels = int64_t(256) * 256 * 256;
    bool operator==(const StylizerVolume&) const = default;
};

/// The transfer function F (SPEC §7): an RGBA image over (V̄ ∈ [0, 1] left to right, linear
/// depth d = (s − depthRange₀)/(depthRange₁ − depthRange₀) ∈ [0, 1] bottom to top), sampled
/// bilinearly between texel centres and clamped at the edges.
/// Either an image, or a stack of layers (core/stylize/tf_layers.h) compiled into `image` at
/// width × height (compileTransferFunction); constraints anchored in the scene move with it, so
/// their stack is compiled again for each frame (core/stylize/tf_anchors.h).
struct TransferFunction {
    enum class Mode { Multiply, Replace };
    std::shared_ptr<const Image> image;
    Mode mode = Mode::Multiply;  ///< multiply: F.rgb scales L_scat; replace: F.rgb·F.a is L_scat
    double depthNear = 0, depthFar = 50;
    std::vector<TfLayer> layers = {};  ///< non-empty: `image` is compiled from these
    int width = 128, height = 128;     ///< the compiled image's size, 1–1024
    bool hasAnchors() const;
    /// Equal looks: a layered TF's compiled image is left out (made again from its layers).
    bool operator==(const TransferFunction& o) const;
};

/// A key of the camera path (issue #15): at `time` the camera is `camera` and the TF is
/// `transferFunction` (none: the scene's own). Between two keys both are interpolated linearly
/// (core/stylize/keyframes.h).
struct StylizerKeyframe {
    double time = 0;
    Camera camera;
    std::optional<TransferFunction> transferFunction = std::nullopt;
    bool operator==(const StylizerKeyframe&) const = default;
};

inline constexpr size_t kMaxKeyframes = 256;
/// Texels × (diffusion layers + 1) of every TF of a scene together: 2 M is about 8 s of
/// compiling on one core (the diffusion solve costs ~4 µs a texel), e.g. 16 keys of 128² with
/// 7 diffusion layers each.
inline constexpr double kMaxTfCompileWork = 2.0e6;

struct StylizerScene {
    std::vector<Occluder> occluders;
    StylizerLight light;
    HomogeneousMedium medium;
    Camera camera;
    Vec3d background{0.02, 0.025, 0.035};  ///< radiance behind everything (night sky)
    double time = 0;
    std::optional<TransferFunction> transferFunction;  ///< none: the physical image
    /// A camera path with key-framed TFs, by increasing time; empty: none. With keys, `time`
    /// places the frame on the path: its camera and TF come from the keys around it.
    std::vector<StylizerKeyframe> keyframes = {};
    /// A heterogeneous medium replacing `medium`'s extinction (its albedo and phase stay).
    std::optional<StylizerVolume> volume = std::nullopt;

    /// The scene's TF and every key's, for what applies to all of them (nulls skipped).
    std::vector<TransferFunction*> transferFunctions();
    std::vector<const TransferFunction*> transferFunctions() const;

    /// Throws InvalidArgument when compiling every TF (its own and its keys') would cost over
    /// kMaxTfCompileWork: checked before anything is compiled, and by validate().
    void checkTfCompileWork() const;

    /// Throws InvalidArgument naming the first problem (a bad mesh, a degenerate
    /// light, a shadow map outside 512–4096, a negative σt, ρ outside [0,1], a bad camera).
    void validate() const;
    bool operator==(const StylizerScene&) const = default;
};

/// How V̄ is found: N midpoint lookups per view ray (the reference), or the exact traversal of
/// the manipulated map's min-max mipmap (stylize.comp; docs/STYLIZER.md has the measurements).
enum class VisibilityMethod { Naive, Accelerated };

struct StylizeSettings {
    VisibilityMethod method = VisibilityMethod::Accelerated;
    int steps = 256;       ///< shadow-map lookups per view ray for V̄ (naive method), 1–4096
    int spotSteps = 64;    ///< midpoint samples of a spot light's in-scattering integral, 1–4096
    /// Read the shadow maps back (their AOVs); off, StylizedFrame::shadowMap and
    /// modifiedShadowMap stay empty and a frame saves two n×n read-backs (live previews).
    bool readShadowMaps = true;
    /// Read the AOVs back (V̄, L_scat, linear depth); off, only the frame comes back, which on a
    /// GPU saves most of a frame's time (live previews). A TF with anchored constraints reads
    /// them whatever this says: it is placed from them.
    bool readAovs = true;
    /// A pixel whose occluder StylizedFrame::pickedOccluder names (a click in the scene).
    struct Pixel {
        int x = 0, y = 0;
    };
    std::optional<Pixel> pick = std::nullopt;
    /// With `pick`: read back only the picked pixel — the frame and every AOV come back 1×1,
    /// holding that pixel (a click on a 4096² frame once read back 1.3 GB of images for it).
    bool pickOnly = false;
    void validate() const;
};

/// What a frame can be saved as (SPEC §7 "Outputs"): the frame or one of its AOVs.
enum class StylizerOutput { Frame, AverageVisibility, LinearDepth, ShadowMap, ModifiedShadowMap, Scattering };
/// The frame and the scattering are pictures (sRGB and exposure in 8-bit files); the other AOVs
/// are data, stored linearly (core::SaveOptions::data).
inline bool isPicture(StylizerOutput o) { return o == StylizerOutput::Frame || o == StylizerOutput::Scattering; }
/// Has a frame read back only what `which` needs: the shadow maps for the map outputs, the AOVs
/// for V̄, depth and the scattering, neither for the frame itself.
inline void readBackOnly(StylizeSettings& settings, StylizerOutput which) {
    settings.readShadowMaps = which == StylizerOutput::ShadowMap || which == StylizerOutput::ModifiedShadowMap;
    settings.readAovs = which == StylizerOutput::AverageVisibility || which == StylizerOutput::LinearDepth ||
                        which == StylizerOutput::Scattering;
}

/// The built-in scene `forest`: a ground plane and a grove of trees whose canopies are clouds of
/// leaf quads, under a low sun, seen from inside a hazy wood: light shafts through foliage.
StylizerScene builtinForest();

}  // namespace volstyle::core
