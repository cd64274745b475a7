// The pixels SVGF's variance and a-trous stages work on. With SVGF_FILTER_LIST (views that take
// other views' filtered light: SVGF_SHARED) the reprojection lists the pixels left to filter, those
// with a surface whose light is their own (svgf_list_pixel), and these stages run over that list,
// dispatched indirectly (glsl/pixel_list.glsl): a view that reuses most of its light has a few
// pixels to filter, scattered over its image, and in 8x8 tiles of the image most lanes of their
// warps would idle. Else they run over the image in 8x8 tiles. Declares the stage's local size.
#pragma once
#ifndef SVGF_FILTER_LIST
#define SVGF_FILTER_LIST 0
#endif
#ifdef SVGF_LIST_WRITER   // the reprojection: the image in 8x8 tiles, and it writes the list
#define PIXEL_LIST_APPEND SVGF_FILTER_LIST
#else
#define PIXEL_LIST_INPUT SVGF_FILTER_LIST
#endif
#include "pixel_list.glsl"

#ifdef SVGF_LIST_WRITER
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
// Lists p when `filtered`; every invocation of the workgroup calls it, in uniform control flow.
void svgf_list_pixel(bool filtered, ivec3 p) {
#if SVGF_FILTER_LIST
    pixel_list_append(filtered, p);
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
    return pixel_list_item(p);
#else
    p = ivec3(gl_GlobalInvocationID);
    return all(lessThan(p, size));
#endif
}
#endif
