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
#ifndef RAY_PASS_COMPACT
#define RAY_PASS_COMPACT 1
#endif
#if RAY_PASS_ACCEPTS
bool ray_pass_accepts(ivec3 p);   // the shader's own test of a pixel the pass would work on
#endif

#if PIXELS_2D
// Pixel p (of the image dispatch) has work: inside, its effect min_effect or above, and (with
// TRACE_DECISION) the trace decision leaves it its rays (gbuffer.glsl must come first).
bool ray_pass_wants(ivec3 p, uint min_effect, ivec3 image_size) {
    if (any(greaterThanEqual(p, image_size))) return false;
    uint effect = gbuf_effect_at(p);
#if TRACE_DECISION
    if (decision_reconstructed(p)) return false;
#endif
    if (effect == GBUF_NO_GEOMETRY || effect < min_effect) return false;
#if RAY_PASS_ACCEPTS
    if (!ray_pass_accepts(p)) return false;
#endif
    return true;
}
#endif

// The pixel a ray pass's invocation works on; false when it has none. From the list (dispatched
// indirectly, PIXEL_LIST_GROUP threads a group) when ray_pass_accepts it, or with PIXELS_2D the
// invocation's own pixel of the image when ray_pass_wants it (then no list is declared).
bool ray_pass_pixel(uint min_effect, ivec3 image_size, out ivec3 p) {
#if PIXELS_2D
    p = ray_group_pixel();
    return ray_pass_wants(p, min_effect, image_size);
#else
    if (!pixel_list_item(p)) return false;
#if RAY_PASS_ACCEPTS
    if (!ray_pass_accepts(p)) return false;
#endif
    return true;
#endif
}

// A ray pass's kernel as batches (every invocation calls ray_pass_batches, in uniform control flow,
// then ray_pass_batch_pixel for each batch b < the count):
//   for (uint b = 0u, n = ray_pass_batches(E, size); b < n; ++b)
//       if (ray_pass_batch_pixel(b, p)) shade(p);
// With RAY_PASS_COMPACT K > 1 (PIXELS_2D, a workgroup of at most 32 invocations, no work tiles) a
// workgroup gathers the pixels ray_pass_wants of K tiles (glsl/tile_gather.glsl); else one batch,
// the invocation's ray_pass_pixel.
uint ray_pass_min_effect;
ivec3 ray_pass_size;
#if PIXELS_2D && RAY_PASS_COMPACT > 1
#define TILE_GATHER RAY_PASS_COMPACT
#include "tile_gather.glsl"
bool tile_gather_wants(ivec3 p) { return ray_pass_wants(p, ray_pass_min_effect, ray_pass_size); }
#endif

uint ray_pass_batches(uint min_effect, ivec3 image_size) {
    ray_pass_min_effect = min_effect;
    ray_pass_size = image_size;
#if PIXELS_2D && RAY_PASS_COMPACT > 1
    return tile_gather();
#else
    return 1u;
#endif
}

bool ray_pass_batch_pixel(uint b, out ivec3 p) {
#if PIXELS_2D && RAY_PASS_COMPACT > 1
    return tile_gather_pixel(b, p);
#else
    return ray_pass_pixel(ray_pass_min_effect, ray_pass_size, p);
#endif
}
#endif
