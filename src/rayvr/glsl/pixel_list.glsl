// Per-effect pixel lists built by the compaction pass (rayvr/passes/compaction/) and consumed
// by the ray passes through ComputeShader.run_indirect. Buffer layout (std430, uint words):
//   [0] pixel count, [1..3] indirect dispatch args (groups x, 1, 1), [4..] packed pixels.
// A pixel packs x (13 bits) | y (13 bits) << 13 | view (6 bits) << 26: up to 8192 px and 64 views.
#pragma once
#ifndef PIXEL_LIST_INPUT
#define PIXEL_LIST_INPUT 0
#endif
#ifndef PIXELS_2D
#define PIXELS_2D 0
#endif
#ifndef PIXEL_LIST_APPEND
#define PIXEL_LIST_APPEND 0
#endif

#define PIXEL_LIST_GROUP 64
#define PIXEL_LIST_HEADER_WORDS 4

#include "pixel_pack.glsl"

// Groups of PIXEL_LIST_GROUP a list's indirect dispatch gains when a writer appends [base, base + n)
// to the [0, base) before it (each workgroup adds its own: the count grows as the list fills).
uint pixel_list_new_groups(uint base, uint n) {
    const uint g = PIXEL_LIST_GROUP;
    return (base + n + g - 1u) / g - (base + g - 1u) / g;
}

#include "ray_group.glsl"
#include "trace_decision.glsl"

#if PIXEL_LIST_INPUT   // a pass that reads a list (bound to the block PixelList by name)
layout(std430) readonly buffer PixelList {
    uint pixel_count;
    uint pixel_dispatch[3];
    uint pixel_items[];
};
// The pixel of this invocation of a dispatch over the list (indirect, PIXEL_LIST_GROUP threads a
// group); false past its end.
bool pixel_list_item(out ivec3 p) {
    uint i = gl_GlobalInvocationID.x;
    p = ivec3(0);
    if (i >= pixel_count) return false;
    p = pixel_list_unpack(pixel_items[i]);
    return true;
}
#endif

#if PIXEL_LIST_APPEND   // a pass that writes one list (the block AppendList), its workgroups' pixels
layout(std430) buffer AppendList {
    uint append_count;
    uint append_dispatch[3];
    uint append_items[];
};
shared uint s_append_count;
shared uint s_append_base;
// Appends p to the list when `listed`: one global atomic per workgroup. Every invocation of the
// workgroup calls it, in uniform control flow (it holds barriers).
void pixel_list_append(bool listed, ivec3 p) {
    if (gl_LocalInvocationIndex == 0u) s_append_count = 0u;
    barrier();
    uint local = listed ? atomicAdd(s_append_count, 1u) : 0u;
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_append_count > 0u) {
        s_append_base = atomicAdd(append_count, s_append_count);
        atomicAdd(append_dispatch[0], pixel_list_new_groups(s_append_base, s_append_count));
    }
    barrier();
    if (listed) append_items[s_append_base + local] = pixel_list_pack(p);
}
#endif

#if PIXEL_LIST_INPUT || PIXELS_2D
// The pixel a ray pass's invocation works on; false when it has none. From the list (dispatched
// indirectly, PIXEL_LIST_GROUP threads a group), or with PIXELS_2D the invocation's own pixel of
// the image when its effect is min_effect or above and (TRACE_DECISION) the trace decision leaves
// it its rays (then gbuffer.glsl must come first, and no list is declared).
bool ray_pass_pixel(uint min_effect, ivec3 image_size, out ivec3 p) {
#if PIXELS_2D
    p = ray_group_pixel();
    if (any(greaterThanEqual(p, image_size))) return false;
    uint effect = gbuf_effect_at(p);
#if TRACE_DECISION
    if (decision_reconstructed(p)) return false;
#endif
    return effect != GBUF_NO_GEOMETRY && effect >= min_effect;
#else
    return pixel_list_item(p);
#endif
}
#endif
