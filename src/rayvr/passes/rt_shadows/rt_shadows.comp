// Emission + ray-traced shadowed direct light for the pixels whose effect is SHADOWS or above: those
// on the shadow list (indirect dispatch), or with PIXELS_2D every pixel of the image in tiles;
// + the probes' indirect diffuse light with PROBE_GI.
#define GBUF_READER 1
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

void main() {
    ivec3 p;
    if (!ray_pass_pixel(EFFECT_SHADOWS, imageSize(dst), p)) return;
    GSurface g = gbuf_load(p);
    Rng rng = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT);
    rq_blend_begin(rng);   // alphaMode BLEND: this pixel's decisions
    PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
    // REFLECTIONS and above: RTReflections traces the specular lobes and shares their light (MIS)
    vec3 c = g.emissive + shade_direct_mis(s, rng, g.effect >= EFFECT_REFLECTIONS) + probe_gi_diffuse(s);
    imageStore(dst, p, vec4(to_half_range(nonfinite_scrub(c)), 1.0));   // the target is rgba16f
    ray_count_commit(uint(p.z));
}
