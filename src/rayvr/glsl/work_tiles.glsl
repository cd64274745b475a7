// The trace decision's work tiles (TraceDecision's `workTiles`, where SVGF spreads reused light):
// the WORK_TILE_X x WORK_TILE_Y pixel tiles of one view that hold a pixel whose light is not
// another view's, in the pixel list layout (glsl/pixel_list.glsl: [count, groups x, 1, 1, then
// each tile packed as a pixel: tile x, tile y, view]), one workgroup a tile. A pass whose
// workgroup is such a tile (ray_group.glsl, 8 x 4 x 1) and which leaves the spread pixels alone
// runs over the list, indirectly (WORK_TILES_INPUT 1): the tiles whose every pixel borrows its
// light launch no workgroup. In a view that reuses most of its light most tiles do, and a
// ray pass's register-heavy workgroups would each wait out two fetches only to leave.
#pragma once
#include "pixel_pack.glsl"
#ifndef WORK_TILES_INPUT
#define WORK_TILES_INPUT 0
#endif
#ifndef WORK_TILES_APPEND
#define WORK_TILES_APPEND 0
#endif
const uint WORK_TILE_X = 8u;
const uint WORK_TILE_Y = 4u;

#if WORK_TILES_INPUT
layout(std430) readonly buffer WorkTiles {
    uint work_tile_count;
    uint work_tile_dispatch[3];
    uint work_tile_items[];
};
// This workgroup's tile: x and y in tiles, the view.
uvec3 work_tile() { return uvec3(pixel_list_unpack(work_tile_items[gl_WorkGroupID.x])); }
#endif

#if WORK_TILES_APPEND   // the writer, in 8x8 workgroups: two tiles each, one above the other
layout(std430) buffer WorkTiles {
    uint work_tile_count;
    uint work_tile_dispatch[3];
    uint work_tile_items[];
};
shared uint s_work_tiles;   // bit h: the workgroup's tile h has work
// Lists the workgroup's tiles in which some invocation has `work`: one global atomic per
// workgroup and count. Every invocation calls it, in uniform control flow (it holds barriers).
void work_tiles_append(bool work) {
    if (gl_LocalInvocationIndex == 0u) s_work_tiles = 0u;
    barrier();
    if (work) atomicOr(s_work_tiles, 1u << (gl_LocalInvocationID.y / WORK_TILE_Y));
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_work_tiles != 0u) {
        uint n = uint(bitCount(s_work_tiles));
        uint base = atomicAdd(work_tile_count, n);
        atomicAdd(work_tile_dispatch[0], n);
        for (uint h = 0u; h < 2u; ++h)
            if ((s_work_tiles & (1u << h)) != 0u)
                work_tile_items[base++] = pixel_list_pack(ivec3(gl_WorkGroupID.x, gl_WorkGroupID.y * 2u + h,
                                                                gl_WorkGroupID.z));
    }
}
#endif
