// layout.h is compiled as C++ here and as GLSL in the kernels: the std140 block must have the
// same offsets on both sides (NanoVDB TestOffsets). std140 puts vec4/ivec4 at 16-byte strides and
// a mat4 at 64 bytes, so every member's offset is fixed by the order below.
#include <gtest/gtest.h>

#include <cstddef>

#include "core/shaders/layout.h"

using volstyle::core::layout::MarchParams;

static_assert(sizeof(volstyle::core::layout::Float4) == 16);
static_assert(sizeof(volstyle::core::layout::Int4) == 16);
static_assert(sizeof(volstyle::core::layout::Float4x4) == 64);
static_assert(offsetof(MarchParams, indexFromWorld) == 0);
static_assert(offsetof(MarchParams, eye) == 64);
static_assert(offsetof(MarchParams, camForward) == 80);
static_assert(offsetof(MarchParams, dims) == 144);
static_assert(offsetof(MarchParams, march) == 192);
static_assert(offsetof(MarchParams, lightDirection) == 240);
static_assert(offsetof(MarchParams, lightIrradiance) == 240 + 16 * volstyle::core::layout::kLightSlots);
static_assert(offsetof(MarchParams, lightKernel) == 240 + 32 * volstyle::core::layout::kLightSlots);
static_assert(offsetof(MarchParams, unknownDims) == 240 + 32 * volstyle::core::layout::kLightSlots + 16);
static_assert(offsetof(MarchParams, viewPixels) == 240 + 32 * volstyle::core::layout::kLightSlots + 64);
static_assert(offsetof(MarchParams, dispatchOffset) == 240 + 32 * volstyle::core::layout::kLightSlots + 96);
static_assert(offsetof(MarchParams, lightGridFromIndex) == 240 + 32 * volstyle::core::layout::kLightSlots + 112);
static_assert(offsetof(MarchParams, lightGridDims) == 240 + 96 * volstyle::core::layout::kLightSlots + 112);
static_assert(offsetof(MarchParams, indexFromLightGrid) == 240 + 112 * volstyle::core::layout::kLightSlots + 112);
static_assert(offsetof(MarchParams, lobeGrid) == 240 + 112 * volstyle::core::layout::kLightSlots + 176);
static_assert(offsetof(MarchParams, sparseOffset) == 240 + 112 * volstyle::core::layout::kLightSlots + 224);
static_assert(sizeof(MarchParams) == 240 + 112 * volstyle::core::layout::kLightSlots + 240);
static_assert(sizeof(volstyle::core::layout::LobeParams) == 32 * volstyle::core::layout::kMaxLobeSlots);
static_assert(sizeof(volstyle::core::layout::VectorParams) == 80);
static_assert(offsetof(volstyle::core::layout::StylizeParams, options) == 384);
static_assert(offsetof(volstyle::core::layout::StylizeParams, mipOffset) == 432);
static_assert(offsetof(volstyle::core::layout::StylizeParams, volumeLo) == 496);  // issue #15's heterogeneous medium
static_assert(offsetof(volstyle::core::layout::StylizeParams, volumeScale) == 528);  // issue #36: the session volume's scale
static_assert(sizeof(volstyle::core::layout::StylizeParams) == 560);
static_assert(sizeof(volstyle::core::layout::EditParams) == 64);

TEST(Layout, MarchParamsMatchesStd140) {
    // The static_asserts above are the test; this records the size in the test log.
    // 416 bytes before issue #8 named the light index, pixel offset and cut-off (lightKernel,
    // viewPixels, projectorCutoff) instead of hiding them in spare components; 480 since #9 added
    // dispatchOffset for chunked (budgeted) dispatches; 864 since #10 put light depth on
    // light-aligned grids (lightGridFromIndex, lightGridDims, indexFromLightGrid); 912 since #13
    // added the environment lobes' light volumes (lobeGrid, lobeScale, lobeKernel); 928 since #39
    // stored sparse volumes as bricks (sparseOffset).
    EXPECT_EQ(sizeof(MarchParams), 928u);
}

TEST(Layout, SolverVocabularyIsSharedWithTheShaders) {
    // The C++ enums take their values from layout.h; the shaders compare VOLSTYLE_UNKNOWN etc. to
    // the same macros. These pin the values so a renumbering shows in review.
    EXPECT_EQ(VOLSTYLE_UNKNOWN_EMISSION, 1);
    EXPECT_EQ(VOLSTYLE_UNKNOWN_EXTINCTION, 4);
    EXPECT_EQ(VOLSTYLE_OP_AXPY, 1);
    EXPECT_EQ(VOLSTYLE_OP_CLAMP, 8);
}
