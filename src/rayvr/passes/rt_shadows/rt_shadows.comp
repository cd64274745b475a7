// Emission + ray-traced shadowed direct light for the pixels whose effect is SHADOWS or above: those
// on the shadow list (indirect dispatch), or with PIXELS_2D every pixel of the image in tiles;
// + the probes' indirect diffuse light with PROBE_GI.
// With SHARED_LIGHT (a trace decision over several views, one light sample): the traced pixels of
// effect SHADOWS and REFLECTIONS record their sample (shading.glsl SharedLight) in `shared_lights`;
// a pixel the decision flags DECISION_SHARED_LIGHT traces no ray of its own: a second dispatch of
// this shader, built with SHARED_LIGHT_TAKE, shades its own lobes over its source pixel's sample.
// With RAY_PASS_COMPACT (glsl/pixel_list.glsl) a workgroup works through the pixels of several
// tiles in full batches.
#define GBUF_READER 1
#ifndef SHARED_LIGHT
#define SHARED_LIGHT 0
#endif
#ifndef SHARED_LIGHT_TAKE
#define SHARED_LIGHT_TAKE 0
#endif
#define RAY_PASS_ACCEPTS SHARED_LIGHT   // each dispatch its own pixels (ray_pass_accepts below)
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "shading.glsl"
#include "probe_gi.glsl"
#include "nonfinite.glsl"
#include "ray_counters.glsl"

#if PIXELS_2D   // every pixel of the image; those whose effect needs no such rays leave at once
layout(local_size_x = RAY_GROUP_SIZE) in;
#else           // the pixels on the list
layout(local_size_x = PIXEL_LIST_GROUP) in;
#endif
layout(rgba16f) writeonly uniform image2DArray dst;
#if SHARED_LIGHT
layout(rgba32ui) uniform uimage2DArray shared_lights;

// The pixels that take their source's light sample are the second dispatch's, the others the first's.
bool ray_pass_accepts(ivec3 p) { return decision_shared_light(decision_at(p)) == bool(SHARED_LIGHT_TAKE); }
#endif

void shade(ivec3 p) {
#if SHARED_LIGHT_TAKE
    uvec2 t = decision_at(p);
#endif
    GSurface g = gbuf_load(p);
    PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
    vec3 direct;
    // REFLECTIONS and above: RTReflections traces the specular lobes and shares their light (MIS)
    bool specular_traced = g.effect >= EFFECT_REFLECTIONS;
#if SHARED_LIGHT_TAKE
    direct = shade_direct_from(s, shared_light_unpack(imageLoad(shared_lights, decision_source(t))), specular_traced);
#else
    Rng rng = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT);
    rq_blend_begin(rng);   // alphaMode BLEND: this pixel's decisions
#if SHARED_LIGHT
    if (g.effect <= EFFECT_REFLECTIONS) {
        SharedLight record;
        direct = shade_direct_shared(s, rng, specular_traced, record);
        imageStore(shared_lights, p, shared_light_pack(record));
    } else
#endif
    direct = shade_direct_mis(s, rng, specular_traced);
#endif
    vec3 c = g.emissive + direct + probe_gi_diffuse(s);
    imageStore(dst, p, vec4(to_half_range(nonfinite_scrub(c)), 1.0));   // the target is rgba16f
    ray_count_commit(uint(p.z));
}

void main() {
    ivec3 p;
    for (uint b = 0u, n = ray_pass_batches(EFFECT_SHADOWS, imageSize(dst)); b < n; ++b)
        if (ray_pass_batch_pixel(b, p)) shade(p);
}
