// bench/sparse_sampling (issue #39): the same march through a volume stored three ways, to pick
// the sparse structure on measurements. Each invocation marches one ray along +z through the
// N³ index box at half-voxel steps, trilinear between voxel centres as common/volume.glsl
// (8 fetches a sample), and writes the optical depth it gathered.
//   METHOD 0: a dense R32F 3D texture (today's layout)
//   METHOD 1: 8³ bricks in an R32F atlas, an R32UI indirection texture (0: empty, else index + 1)
//   METHOD 2: a NanoVDB grid in a storage buffer, read through PNanoVDB (Debian's libnanovdb-dev)
//   METHOD 3: as 1, one table lookup for a cell whose 8 corners share a brick (a branch)
layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) writeonly buffer Depths { float depths[]; };
uniform int uSize;   // rays per side
uniform int uN;      // voxels per side
uniform ivec3 uAtlasBricks;

#if METHOD == 0
layout(binding = 0) uniform sampler3D s_dense;
float voxel(ivec3 p) { return texelFetch(s_dense, p, 0).r; }
#elif METHOD == 1 || METHOD == 3
layout(binding = 0) uniform sampler3D s_atlas;
layout(binding = 1) uniform usampler3D s_table;
float voxel(ivec3 p) {
    uint b = texelFetch(s_table, p >> 3, 0).r;
    if (b == 0u) return 0.0;
    b -= 1u;
    const uint bx = uint(uAtlasBricks.x), by = uint(uAtlasBricks.y);
    const ivec3 brick = ivec3(b % bx, (b / bx) % by, b / (bx * by));
    return texelFetch(s_atlas, brick * 8 + (p & 7), 0).r;
}
#else
layout(std430, binding = 1) readonly buffer Nano { uint pnanovdb_buf_data[]; };
#define PNANOVDB_GLSL
#include "nanovdb/PNanoVDB.h"
pnanovdb_readaccessor_t g_acc;  // per invocation: the accessor caches the path to the last leaf
pnanovdb_buf_t g_buf;
float voxel(ivec3 p) {
    pnanovdb_address_t a = pnanovdb_readaccessor_get_value_address(PNANOVDB_GRID_TYPE_FLOAT, g_buf, g_acc, p);
    return pnanovdb_read_float(g_buf, a);
}
#endif

#if METHOD == 3
// The common case: a cell's 8 corners in one brick, one table lookup for all of them.
bool oneBrick(ivec3 i0, ivec3 i1, out ivec3 base) {
    if (any(notEqual(i0 >> 3, i1 >> 3))) return false;
    uint b = texelFetch(s_table, i0 >> 3, 0).r;
    if (b == 0u) {
        base = ivec3(-1);
        return true;
    }
    b -= 1u;
    const uint bx = uint(uAtlasBricks.x), by = uint(uAtlasBricks.y);
    base = ivec3(b % bx, (b / bx) % by, b / (bx * by)) * 8;
    return true;
}
#endif

float trilinear(vec3 p) {
    vec3 q = clamp(p, vec3(0.0), vec3(uN - 1));
    ivec3 i0 = min(ivec3(floor(q)), ivec3(uN - 1)), i1 = min(i0 + 1, ivec3(uN - 1));
    vec3 f = q - vec3(i0);
#if METHOD == 3
    ivec3 base;
    if (oneBrick(i0, i1, base)) {
        if (base.x < 0) return 0.0;  // an empty brick
        float d000 = texelFetch(s_atlas, base + (i0 & 7), 0).r, d100 = texelFetch(s_atlas, base + (ivec3(i1.x, i0.y, i0.z) & 7), 0).r;
        float d010 = texelFetch(s_atlas, base + (ivec3(i0.x, i1.y, i0.z) & 7), 0).r, d110 = texelFetch(s_atlas, base + (ivec3(i1.x, i1.y, i0.z) & 7), 0).r;
        float d001 = texelFetch(s_atlas, base + (ivec3(i0.x, i0.y, i1.z) & 7), 0).r, d101 = texelFetch(s_atlas, base + (ivec3(i1.x, i0.y, i1.z) & 7), 0).r;
        float d011 = texelFetch(s_atlas, base + (ivec3(i0.x, i1.y, i1.z) & 7), 0).r, d111 = texelFetch(s_atlas, base + (i1 & 7), 0).r;
        float e00 = mix(d000, d100, f.x), e10 = mix(d010, d110, f.x), e01 = mix(d001, d101, f.x), e11 = mix(d011, d111, f.x);
        return mix(mix(e00, e10, f.y), mix(e01, e11, f.y), f.z);
    }
#endif
    float c000 = voxel(i0), c100 = voxel(ivec3(i1.x, i0.y, i0.z)), c010 = voxel(ivec3(i0.x, i1.y, i0.z));
    float c110 = voxel(ivec3(i1.x, i1.y, i0.z)), c001 = voxel(ivec3(i0.x, i0.y, i1.z)), c101 = voxel(ivec3(i1.x, i0.y, i1.z));
    float c011 = voxel(ivec3(i0.x, i1.y, i1.z)), c111 = voxel(i1);
    float c00 = mix(c000, c100, f.x), c10 = mix(c010, c110, f.x), c01 = mix(c001, c101, f.x), c11 = mix(c011, c111, f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= uSize || px.y >= uSize) return;
#if METHOD == 2
    g_buf.unused = 0u;
    pnanovdb_grid_handle_t grid;
    grid.address.byte_offset = 0u;
    pnanovdb_readaccessor_init(g_acc, pnanovdb_tree_get_root(g_buf, pnanovdb_grid_get_tree(g_buf, grid)));
#endif
    vec2 xy = (vec2(px) + 0.5) / float(uSize) * float(uN) - 0.5;
    float depth = 0.0;
    for (float z = -0.5; z <= float(uN) - 0.5; z += 0.5) depth += 0.5 * trilinear(vec3(xy, z));
    depths[px.y * uSize + px.x] = depth;
}
