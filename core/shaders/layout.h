/* layout.h — shared by C++ and GLSL (STYLE §3.5, PNanoVDB style): the std140 uniform block of the
 * ray-marching kernels, binding points and workgroup sizes. The GLSL loader defines VOLSTYLE_GLSL;
 * the C++ side maps the vector types to 16-byte aligned structs. tests/unit/layout_test.cpp checks
 * sizes and offsets. Only vec4/ivec4/mat4 members: std140 then equals the C++ layout. */
#ifndef VOLSTYLE_LAYOUT_H
#define VOLSTYLE_LAYOUT_H

#ifdef VOLSTYLE_GLSL
#define VS_VEC4 vec4
#define VS_IVEC4 ivec4
#define VS_MAT4 mat4
#define VS_CONSTANT(type, name, value) const type name = value
#else
#include <cstdint>
namespace volstyle::core::layout {
struct alignas(16) Float4 { float x = 0, y = 0, z = 0, w = 0; };
struct alignas(16) Int4 { int32_t x = 0, y = 0, z = 0, w = 0; };
struct alignas(16) Float4x4 { float m[16] = {}; };  /* column-major, as GLSL mat4 */
#define VS_VEC4 Float4
#define VS_IVEC4 Int4
#define VS_MAT4 Float4x4
#define VS_CONSTANT(type, name, value) constexpr type name = value
#endif

VS_CONSTANT(int, kWorkgroup2D, 8);   /* render kernel: 8x8 pixels */
VS_CONSTANT(int, kWorkgroup3D, 4);   /* volume kernels: 4x4x4 voxels */
VS_CONSTANT(int, kBrickSize, 8);     /* occupancy brick edge, in voxels */
VS_CONSTANT(int, kLightSlots, 4);    /* light-depth volumes bound at once */
/* Optical depth toward a light at a sample (common/lighting.glsl lightDepthAt, issue #34): marched
 * from the sample itself over its first node spans, then read from the light-depth grid. The march
 * covers at least kLightMarchMinNodes of the grid's along-beam spacing, goes on while a span held
 * at least kLightMarchDenseSpan optical depth, for at most kLightMarchMaxSpans spans past the
 * first node plane, and stops once kLightMarchOpaque is gathered (e^-12 ≈ 6e-6 of the light left). */
VS_CONSTANT(float, kLightMarchMinNodes, 1.0);
VS_CONSTANT(int, kLightMarchMaxSpans, 3);
VS_CONSTANT(float, kLightMarchDenseSpan, 0.1);
VS_CONSTANT(float, kLightMarchOpaque, 12.0);
/* Dense segments of a view ray (common/march.glsl splitDense, issue #34): a segment whose occupancy
 * brick (the largest extinction within a voxel of it) allows more than kMarchDenseSegmentDepth
 * optical depth is cut into equal sub-segments of at most that depth, at most kMarchMaxSubsegments
 * of them. The midpoint quadrature misses how fast in-scattering changes in such media: with the
 * exact light integral, a cloud of 4 optical depths a voxel lit from the side is 3.5% RMS off at a
 * step of 0.5 voxel, 0.6% cut at 1 and 0.2% at 0.5. At 1, media below 2 optical depths a voxel (the
 * built-in cloud at 64³: 1.25, ≤ 1.05% uncut) pay nothing; cutting at 0.5 cost it 1.9× a frame.
 * The bound is the brick at the segment's midpoint, whose one-voxel apron covers the segment for
 * steps up to a voxel; a coarser step (a preview's) can cross a denser brick uncut. */
VS_CONSTANT(float, kMarchDenseSegmentDepth, 1.0);
VS_CONSTANT(int, kMarchMaxSubsegments, 8);

/* Kinds of solver unknowns (VOLSTYLE_UNKNOWN in project.comp; core::Unknown takes these values)
 * and bases (VOLSTYLE_BASIS; core::BasisType). Macros: GLSL compares them in #if. */
#define VOLSTYLE_UNKNOWN_EMISSION 1
#define VOLSTYLE_UNKNOWN_ALBEDO 2
#define VOLSTYLE_UNKNOWN_EMISSION_ALBEDO 3
#define VOLSTYLE_UNKNOWN_EXTINCTION 4
#define VOLSTYLE_BASIS_BOX 0
#define VOLSTYLE_BASIS_TRILINEAR 1

/* Operations of vector_ops.comp (VOLSTYLE_OP; core::VectorOps::Op takes these values). */
#define VOLSTYLE_OP_AXPY 1
#define VOLSTYLE_OP_XPBY 2
#define VOLSTYLE_OP_MUL 3
#define VOLSTYLE_OP_DOT 4
#define VOLSTYLE_OP_LAPLACIAN 5
#define VOLSTYLE_OP_FREE 6
#define VOLSTYLE_OP_STEP 7
#define VOLSTYLE_OP_CLAMP 8
#define VOLSTYLE_OP_MAXCHANGE 9
#define VOLSTYLE_OP_DOT_SEGMENTS 10

/* Binding points. */
VS_CONSTANT(int, kBindingParams, 0);       /* UBO MarchParams */
VS_CONSTANT(int, kBindingImageOut, 0);     /* SSBO vec4 pixels[] */
VS_CONSTANT(int, kBindingLayersOut, 1);    /* SSBO vec4 layers[kRenderLayers][pixels] (render.comp, VOLSTYLE_LAYERS) */
VS_CONSTANT(int, kRenderLayers, 5);        /* medium (premultiplied), emission, scattering, transmittance, background */
VS_CONSTANT(int, kRenderLayersWithAlbedoOne, 6);  /* and the scattering at albedo 1 (VOLSTYLE_ALBEDO_ONE_LAYER: the solver's reach analysis) */
VS_CONSTANT(int, kUnitExtinction, 0);
VS_CONSTANT(int, kUnitAlbedo, 1);
VS_CONSTANT(int, kUnitEmission, 2);
VS_CONSTANT(int, kUnitEnvironment, 3);
VS_CONSTANT(int, kUnitOccupancy, 4);
VS_CONSTANT(int, kUnitBrickTable, 11);    /* sparse volumes: usampler3D r32ui, per brick the atlas brick its voxels are in (packed by kAtlasBits) */
VS_CONSTANT(int, kAtlasBits, 10);         /* bits per axis of a packed atlas brick coordinate */
VS_CONSTANT(int, kUnitLightDepth0, 5);     /* 5..8 */
VS_CONSTANT(int, kImageUnitOut, 0);        /* image store target of volume kernels */
VS_CONSTANT(int, kBindingUnknown, 1);      /* SSBO: the solver's unknown coefficients (3 per voxel) */
VS_CONSTANT(int, kBindingResidual, 2);     /* SSBO vec4 per pixel: residual read by the adjoint */
VS_CONSTANT(int, kBindingVectorX, 3);      /* SSBOs of the vector kernels */
VS_CONSTANT(int, kBindingVectorY, 4);
VS_CONSTANT(int, kBindingVectorZ, 5);
VS_CONSTANT(int, kBindingPartials, 6);     /* per-workgroup partial sums (dvec4) */
VS_CONSTANT(int, kWorkgroup1D, 256);
VS_CONSTANT(int, kBindingIndexList, 7);
VS_CONSTANT(int, kBindingSegments, 10);    /* VOLSTYLE_OP_DOT_SEGMENTS: uvec2[workgroups], each one's (first position, count) */
/* Refracted view rays (common/march.glsl, VOLSTYLE_CURVED; core/render/refracted_paths.h). */
VS_CONSTANT(int, kBindingPathStart, 8);   /* SSBO uint[pixels + 1]: pixel p's vertices are [start[p], start[p+1]) */
VS_CONSTANT(int, kBindingPathVertex, 9);  /* SSBO vec4[]: index-space position, arc length from the eye (world) */
VS_CONSTANT(int, kBindingUnknownSlots, 11);  /* VOLSTYLE_SPARSE projector: SSBO uint[bricks of the unknown grid]: slot, 0 inactive */
VS_CONSTANT(int, kBindingPathExit, 10);   /* SSBO vec4[pixels]: the world direction each ray leaves in (w 0: it misses) */    /* SSBO uint[]: the elements a vector kernel touches (VOLSTYLE_INDEXED) */

/* Everything a march needs: camera, grid, lighting. World-space t parameterises rays. */
struct MarchParams {
    VS_MAT4 indexFromWorld;
    VS_VEC4 eye;             /* xyz: camera position (world) */
    VS_VEC4 camForward;      /* xyz: unit view direction; w: tan(fov_y / 2) */
    VS_VEC4 camRight;        /* xyz: unit right; w: aspect (width / height) */
    VS_VEC4 camUp;           /* xyz: unit up */
    VS_VEC4 rayRange;        /* x: near, y: far (world distance from the eye) */
    VS_IVEC4 dims;           /* xyz: voxels of the extinction grid */
    VS_IVEC4 brickDims;      /* xyz: occupancy bricks */
    VS_IVEC4 imageSize;      /* x: width, y: height (pixels) */
    VS_VEC4 march;           /* x: step (voxels), y: termination budget ε, z: bound on radiance */
    VS_VEC4 background;      /* rgb: constant background radiance; w: ±lobes when the lobes are the background (− for a hemisphere basis), else 0 */
    VS_VEC4 phase;           /* x: 0 isotropic, 1 Henyey-Greenstein; y: g */
    VS_VEC4 lightDirection[kLightSlots];   /* xyz: unit world direction toward the light */
    VS_VEC4 lightIrradiance[kLightSlots];  /* rgb: E_l */
    VS_IVEC4 lightKernel;    /* light_depth.comp: x: the light whose grid it fills (index into lightGrid*) */
    /* The solver's projector (project.comp) only. */
    VS_IVEC4 unknownDims;    /* xyz: voxels of the solver's unknown grid */
    VS_VEC4 unknownScale;    /* xyz: unknown voxels per extinction voxel (both grids span one box) */
    VS_IVEC4 unknownLayout;  /* x: elements per block of unknowns (the albedo block's offset in joint solves); yzw: a sparse unknown grid's brick offset (VOLSTYLE_SPARSE) */
    VS_IVEC4 viewPixels;     /* x: index of this view's first pixel in the solver's pixel vector */
    VS_VEC4 projectorCutoff; /* x: transmittance below which forward and adjoint rays both stop */
    /* Chunked dispatches (chunked_dispatch.h): the first cell (voxel or pixel) of this chunk. */
    VS_IVEC4 dispatchOffset;
    /* Light-depth volumes on light-aligned grids (core/render/light_grid.h), one per light slot. */
    VS_MAT4 lightGridFromIndex[kLightSlots];  /* index-space point -> grid coordinates (nodes at integers) */
    VS_IVEC4 lightGridDims[kLightSlots];      /* xyz: nodes; z runs away from the light; w: 1 along a voxel axis */
    VS_MAT4 indexFromLightGrid;               /* light_depth.comp: the inverse, for light lightKernel.x */
    /* Environment lobes (core/render/lobe_volumes.h): the transmittance toward each lobe on a grid of its own. */
    VS_IVEC4 lobeGrid;    /* xyz: nodes of the light volumes' grid; w: lobes */
    VS_VEC4 lobeScale;    /* xyz: light-volume nodes per extinction voxel (both grids span the voxels' box); w: channels (1 grey, 3 rgb) */
    VS_IVEC4 lobeKernel;  /* lobe_volume.comp: x: the lobe it writes. lights_project.comp: x: first lobe of the chunk, y: its lobes */
    /* Sparse volumes (VOLSTYLE_SPARSE, core/volume/brick_layout.h): voxel v lies in brick (v + xyz) / kBrickSize. */
    VS_IVEC4 sparseOffset;
};

/* The environment's lobes (core/render/environment_lobes.h), a uniform block of their own. */
VS_CONSTANT(int, kMaxLobeSlots, 256);             /* = core::kMaxLobes */
VS_CONSTANT(int, kBindingLobeParams, 1);          /* UBO LobeParams */
VS_CONSTANT(int, kUnitLobeTransmittance, 13);     /* samplerBuffer r32f: [node][lobe][channel] (lobe_volume.comp writes it) */
VS_CONSTANT(int, kLobeChunk, 16);                 /* lobes per adjoint pass of lights_project.comp (its per-invocation sums) */
VS_CONSTANT(int, kBindingLobeSums, 3);            /* SSBO vec4[workgroups * kLobeChunk]: the adjoint's per-workgroup sums per lobe */
struct LobeParams {
    VS_VEC4 direction[kMaxLobeSlots];  /* xyz: unit world direction toward the lobe; w: its solid angle */
    VS_VEC4 radiance[kMaxLobeSlots];   /* rgb: its radiance (the lights unknown's forward: the coefficients) */
};

/* The light-shaft stylizer (core/stylize/, SPEC §7): its raster passes (occluders.raster) and its
 * per-pixel pass (stylize.comp). */
VS_CONSTANT(int, kUnitShadowDepth, 9);     /* the light's shadow map (depth, [0,1]) */
VS_CONSTANT(int, kUnitGBufferSurface, 10); /* camera G-buffer: xyz normal, w distance from the eye (0: no surface) */
VS_CONSTANT(int, kUnitGBufferColour, 11);  /* camera G-buffer: rgb surface colour, w object id (1-based) */
VS_CONSTANT(int, kStylizeLayers, 2);
VS_CONSTANT(int, kUnitTransferFunction, 12); /* the stylizer's transfer function F (RGBA, row 0 = d at its far end) */
VS_CONSTANT(int, kUnitStylizeDensity, 0);      /* heterogeneous medium: σt over its box (r32f 3D, scaled) */
VS_CONSTANT(int, kUnitStylizeTransmittance, 1); /* its optical depth τ_l toward the light per voxel (r32f 3D, stylize_transmittance.comp) */
VS_CONSTANT(int, kUnitStylizeOccupancy, 2);     /* its bricks: the largest σt a trilinear lookup inside each can return (r32f 3D, 0: skip it) */
VS_CONSTANT(int, kBindingScatterDepth, 2);  /* SSBO float[n*n]: the manipulated shadow map V̄ reads (row 0 at the bottom) */       /* AOV planes of stylize.comp: (scattering rgb, V̄), (distance, hit, 0, 0) */

/* A frame's display bytes for a live stream (display_pack.comp, issue #40): linear RGBA floats in
 * b_Image (kBindingImageOut) become sRGB bytes R, G, B, 255 per pixel in b_Display, as a PNG of
 * the frame shows them (exposure, clamp to [0, 1], sRGB, rounded). */
struct DisplayPackParams {
    VS_IVEC4 size;  /* x, y: the frame's width and height */
    VS_VEC4 scale;  /* x: 2^exposure */
};
VS_CONSTANT(int, kBindingDisplayOut, 1);  /* SSBO uint[pixels]: packed RGBX bytes (a read-back slot) */

struct StylizeParams {
    VS_MAT4 lightFromWorld;   /* world -> the light's clip space, [-1,1]³ over the occluders (orthographic) */
    VS_MAT4 clipFromWorld;    /* raster passes: world -> clip of the pass's camera (the light's or the view's) */
    VS_MAT4 worldFromObject;  /* raster passes: the occluder being drawn */
    VS_VEC4 eye;              /* xyz: camera position */
    VS_VEC4 camForward;       /* xyz: unit view direction; w: tan(fov_y / 2) */
    VS_VEC4 camRight;         /* xyz: unit right; w: aspect */
    VS_VEC4 camUp;            /* xyz: unit up */
    VS_IVEC4 imageSize;       /* x, y: frame pixels; z: shadow-map side; w: V̄ steps */
    VS_VEC4 lightDirection;   /* xyz: unit, toward the light */
    VS_VEC4 irradiance;       /* rgb: E */
    VS_VEC4 medium;           /* x: σt; y: ρ; z: 0 isotropic, 1 Henyey-Greenstein; w: g */
    VS_VEC4 background;       /* rgb: radiance behind everything; w: far (distance of a ray that hits nothing) */
    VS_VEC4 surface;          /* raster passes: rgb colour of the occluder; w: its id (1-based) */
    VS_VEC4 shadow;           /* x: depth bias (light clip depth units); y: whether a shadow map exists; z: texel size (world) */
    VS_VEC4 transfer;         /* x: 0 none, 1 multiply, 2 replace; y, z: the depth range mapped to d = 0 and 1 */
    VS_IVEC4 options;         /* x: V̄ method (kVisibility*); y: min-max mipmap levels; z: light (kStylizerLight*); w: spot integral steps */
    VS_VEC4 spot;             /* xyz: the spot's position; w: cos of half its cone (no light outside) */
    VS_VEC4 spotCone;         /* x: cos of the inner half-angle (full intensity inside) */
    VS_IVEC4 mipOffset[4];    /* min-max level k starts at entry mipOffset[k / 4][k % 4] of b_MinMax */
    VS_VEC4 volumeLo;         /* heterogeneous medium (issue #15): xyz its box's low corner; w steps along a view ray (0: homogeneous) */
    VS_VEC4 volumeHi;         /* xyz its box's high corner; w 1: the volume's transmittance toward the light dims it */
    VS_VEC4 volumeScale;      /* x: extinction_scale (σt = x × the mean of the volume's RGB extinction) */
    VS_IVEC4 pixelOrigin;     /* xy: the first pixel this dispatch shades (a pick shades its one pixel) */
};
/* A sparse volume's stylizer medium (issue #39; stylize_extinction_mean.comp with VOLSTYLE_SPARSE,
 * stylize_medium_occupancy.comp): the mean of its RGB σt over blocks of w³ voxels, and the bricks
 * of that grid for empty-space skipping. */
struct StylizeMediumParams {
    VS_IVEC4 dims;          /* xyz: the volume's voxels; w: the block side (voxels per medium voxel a side) */
    VS_IVEC4 sparseOffset;  /* xyz: where voxel 0 lies in its brick */
};
VS_CONSTANT(int, kVisibilityNaive, 0);   /* N midpoint lookups of the manipulated map per view ray */
VS_CONSTANT(int, kVisibilityMinMax, 1);  /* exact traversal of its min-max mipmap (stylize.comp) */
VS_CONSTANT(int, kStylizerLightDirectional, 0);
VS_CONSTANT(int, kStylizerLightSpot, 1);
VS_CONSTANT(int, kMaxMinMaxLevels, 16);
VS_CONSTANT(int, kBindingMinMax, 3);     /* SSBO uint[]: the manipulated map, then its min-max levels (common/min_max_entry.glsl) */

/* The min-max mipmap build (shadow_minmax.comp): level k + 1 from level k, 2×2 entries per entry. */
struct MinMaxParams {
    VS_IVEC4 level;  /* x: source side; y: destination side; z: source offset; w: destination offset (entries) */
};

/* Occluder manipulation on the shadow map (shadow_morphology.comp): one pass of running extrema
 * (van Herk / Gil-Werman) along every row or column of an n×n depth map. */
VS_CONSTANT(int, kBindingMorphIn, 1);      /* SSBO float[n*n]: the pass's input */
VS_CONSTANT(int, kBindingMorphOut, 2);     /* SSBO float[n*n]: its output */
VS_CONSTANT(int, kBindingMorphScratch, 3); /* SSBO float[2 * lines * (n + 2 * halfWidth)]: running extrema */
struct MorphParams {
    VS_IVEC4 size;  /* x: n (the map's side); y: half-width w of the 1D window; z: 0 rows, 1 columns, 2 diagonals, 3 anti-diagonals; w: row offset dy */
    VS_IVEC4 op;    /* x: 0 minimum (dilation of occluders), 1 maximum (erosion); y: 1 combine with the output by op, 0 overwrite; z: first line of this dispatch */
};

/* Per-object edits of the scattering's shadow map in place (SPEC §7): the 1D epipolar dilation of
 * Eq. 3 (shadow_dilate.comp) and Perlin-noise holes of Eq. 4–5 (shadow_holes.comp). */
VS_CONSTANT(int, kBindingEditIn, 1);   /* SSBO float[n*n] */
VS_CONSTANT(int, kBindingEditOut, 2);  /* SSBO float[n*n] */
struct EditParams {
    VS_IVEC4 size;      /* x: n; y: dilation kernel length (texels); z: noise octaves; w: noise seed */
    VS_VEC4 epipole;    /* xy: the camera projected into the map (texel coordinates); z: its depth; w: 1 dilate away from it, -1 toward it (camera behind a spot) */
    VS_VEC4 holeFrame;  /* xy: noise coordinates of texel (0, 0)'s corner; zw: their step per texel in x and y */
    VS_VEC4 holeNoise;  /* x: threshold h (holes where N < h); y: persistence; zw: the time offset of the first lookup */
};

/* The solver's cached rows of W (core/solve/sparse_rows.h): project.comp with VOLSTYLE_ROWS
 * counts (1) or writes (2) each view's rows and their transpose; sparse_project.comp applies W
 * from the rows and Wᵀ from the columns. Weights are 1 float per entry (grey) or 3 (rgb). */
#define VOLSTYLE_ROWS_COUNT 1
#define VOLSTYLE_ROWS_FILL 2
VS_CONSTANT(int, kBindingRowStart, 1);    /* SSBO uint[pixels + 1]: count pass: entries per row; fill: first entry */
VS_CONSTANT(int, kBindingRowIndex, 2);    /* SSBO uint[entries]: the element (unknown) of each row entry */
VS_CONSTANT(int, kBindingRowWeight, 3);   /* SSBO float[entries * channels] */
VS_CONSTANT(int, kBindingColStart, 4);    /* SSBO uint[elements + 1]: count pass: entries per column; fill: first entry */
VS_CONSTANT(int, kBindingColCursor, 5);   /* SSBO uint[elements]: fill pass: entries written per column so far */
VS_CONSTANT(int, kBindingColIndex, 6);    /* SSBO uint[entries]: the pixel (within the view) of each column entry */
VS_CONSTANT(int, kBindingColWeight, 7);   /* SSBO float[entries * channels] */
VS_CONSTANT(int, kBindingRowMask, 0);     /* SSBO vec4[pixels] (VOLSTYLE_ROW_MASK): rays of pixels whose weight is 0 write no entries */
VS_CONSTANT(int, kBindingSparseIn, 1);    /* sparse_project.comp: SSBO vec4[]: a (W) or the residual (Wᵀ) */
VS_CONSTANT(int, kBindingSparseOut, 2);   /* SSBO vec4[]: the view's pixels (W) or the unknowns, accumulated (Wᵀ) */
VS_CONSTANT(int, kBindingSparseStart, 3); /* SSBO uint[]: rows' (W) or columns' (Wᵀ) first entries */
VS_CONSTANT(int, kBindingSparseIndex, 4); /* SSBO uint[] */
VS_CONSTANT(int, kBindingSparseWeight, 5);/* SSBO float[] */
VS_CONSTANT(int, kBindingSparseList, 6);  /* SSBO uint[]: the pixels (W) or elements (Wᵀ) to compute, if count.w >= 0 */
struct SparseParams {
    VS_IVEC4 count;  /* x: rows (W) or columns (Wᵀ) of this dispatch; y: offset of the input's first entry; z: of the output's;
                        w: -1, or where this dispatch's part of the list starts (then row/column k is list[w + k], output index included) */
    VS_IVEC4 range;  /* x: the cache's row for output index z (one view's rows within merged rows: its first pixel; else 0);
                        y, z: Wᵀ reads only input pixels in [y, z) (one view of merged columns; else all) */
};

/* Parameters of the vector kernels (vector_ops.comp). Vectors are arrays of vec4 (rgb used). */
struct VectorParams {
    VS_VEC4 alpha;           /* per-channel scalars */
    VS_VEC4 bounds;          /* x, y: lower, upper bound of block 0; z, w: of block 1 */
    VS_IVEC4 count;          /* x: elements; y: first element (indexed: first list position); z: elements per block */
    VS_IVEC4 dims;           /* xyz: grid of one block (Laplacian) */
    VS_IVEC4 sparseOffset;   /* VOLSTYLE_SPARSE Laplacian: xyz where voxel 0 lies in its brick (cells: stored voxels, brick_layout.h) */
};
VS_CONSTANT(int, kBindingSlotOfBrick, 8);  /* VOLSTYLE_SPARSE Laplacian: SSBO uint[bricks of the box]: slot, 0 inactive */
VS_CONSTANT(int, kBindingBrickOfSlot, 9);  /* SSBO ivec4[slots]: the brick of each slot */

/* The translucent preview (core/translucent/, SPEC §9; Kniss et al. 2003): half-angle slices
 * rasterized into the eye buffer (blended) and into two ping-pong light buffers (translucent.raster). */
VS_CONSTANT(int, kUnitLightDirect, 14);   /* light buffer: rgb transmittance from the light to the slice */
VS_CONSTANT(int, kUnitLightIndirect, 15);  /* light buffer: rgb indirect light reaching the slice (1 = the light's) */
VS_CONSTANT(int, kUnitPhaseTable, 9);     /* the phase function over cos θ ∈ [-1, 1], texel i at -1 + 2 i / (N - 1) (a 2D texture, one row) */
VS_CONSTANT(int, kPhaseTableSize, 256);
VS_CONSTANT(int, kNoiseSize, 32);         /* the perturbation's noise volume: kNoiseSize³ texels */
VS_CONSTANT(int, kUnitNoise, 10);         /* the perturbation's noise: kNoiseSize³ RGBA, repeating (core/translucent/perturbation.h) */
VS_CONSTANT(int, kIndirectTaps, 8);       /* blur samples on a ring (+ the centre) per light-buffer texel */
struct TranslucentParams {
    VS_MAT4 clipFromWorld;    /* the pass's raster transform: the camera's perspective, or the light buffer's orthographic */
    VS_MAT4 lightUvFromWorld; /* world -> light-buffer texture coordinates in [0,1]² (xy) */
    VS_MAT4 indexFromWorld;   /* world -> the volume's index space */
    VS_IVEC4 dims;            /* xyz: the volume's voxels; w: light-buffer side (texels) */
    VS_VEC4 eye;              /* xyz: camera position */
    VS_VEC4 sliceAxis;        /* xyz: unit half-angle axis s; w: slice spacing (world) */
    VS_VEC4 lightDirection;   /* xyz: unit, toward the light; w: the light's path through one slice, spacing / (l·s) */
    VS_VEC4 irradiance;       /* rgb: E of the light */
    VS_VEC4 phase;            /* x: 0 isotropic, 1 Henyey-Greenstein; y: g */
    VS_VEC4 indirect;         /* x: 1 on; y: blur radius in light-buffer uv (d tan(θ/2), Eq. 9); z: k, σ_i = k σt; w: S (surface shading) */
    VS_VEC4 transport;        /* rgb: 1 − ln(transport colour): σ_i per channel is k σt times this */
    VS_IVEC4 options;         /* x: has emission; y: has albedo */
    VS_VEC4 perturb;          /* x: displacement amplitude (voxels); y: extinction modulation; z: noise texels per voxel (octave 0); w: octaves */
    VS_VEC4 perturbTime;      /* x: animation time */
    VS_IVEC4 sparseOffset;    /* VOLSTYLE_SPARSE: xyz where voxel 0 lies in its brick (common/sparse_grid.glsl) */
};

#ifndef VOLSTYLE_GLSL
}  /* namespace volstyle::core::layout */
#endif
#undef VS_VEC4
#undef VS_IVEC4
#undef VS_MAT4
#undef VS_CONSTANT
#endif
