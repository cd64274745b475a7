// The pixels SVGF's variance and a-trous stages work on. With SVGF_FILTER_LIST (views that take
// other views' filtered light: SVGF_SHARED) the reprojection lists the pixels left to filter, those
// with a surface whose light is their own (svgf_list_pixel), and these stages run over that list,
// dispatched indirectly PIXEL_LIST_GROUP invocations a group (glsl/pixel_list.glsl's layout): a
// view that reuses most of its light filters a few pixels scattered over its image, and in 8x8
// tiles of the image most lanes of their warps would idle. Else they run over the image in 8x8
// tiles. Declares the stage's local size.
#pragma once
#ifndef SVGF_FILTER_LIST
#define SVGF_FILTER_LIST 0
#endif
#include "pixel_list.glsl"

#if SVGF_FILTER_LIST
layout(std430) buffer FilterList {
    uint filter_count;
    uint filter_dispatch[3];
    uint filter_items[];
};
#endif

#ifdef SVGF_LIST_WRITER   // the reprojection: the image in 8x8 tiles, and it writes the list
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
#if SVGF_FILTER_LIST
shared uint s_listed;
shared uint s_base;
#endif
// Appends p to the list when `filtered`: one global atomic per workgroup. Every invocation of the
// workgroup calls it, in uniform control flow (it holds barriers); without the list it does nothing.
void svgf_list_pixel(bool filtered, ivec3 p) {
#if SVGF_FILTER_LIST
    if (gl_LocalInvocationIndex == 0u) s_listed = 0u;
    barrier();
    uint local = filtered ? atomicAdd(s_listed, 1u) : 0u;
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_listed > 0u) {
        s_base = atomicAdd(filter_count, s_listed);
        atomicAdd(filter_dispatch[0], pixel_list_new_groups(s_base, s_listed));
    }
    barrier();
    if (filtered) filter_items[s_base + local] = pixel_list_pack(p);
#endif
}
#else
#if SVGF_FILTER_LIST
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
#endif
// This invocation's pixel of an image `size` in size; false when it has none.
bool svgf_pixel(ivec3 size, out ivec3 p) {
#if SVGF_FILTER_LIST
    uint i = gl_GlobalInvocationID.x;
    p = ivec3(0);
    if (i >= filter_count) return false;
    p = pixel_list_unpack(filter_items[i]);
    return true;
#else
    p = ivec3(gl_GlobalInvocationID);
    return all(lessThan(p, size));
#endif
}
#endif
