// What every stage of ReSTIR DI (restir_di.py) starts with: its pixels, those whose effect is
// SHADOWS or above (the shadow list's, or with PIXELS_2D the whole image in ray_group tiles, where
// the others leave at once), and their surfaces. The reservoir images are rgba32ui, a layer per view.
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "restir_di.glsl"

#if PIXELS_2D
layout(local_size_x = RAY_GROUP_SIZE) in;
#else
layout(local_size_x = PIXEL_LIST_GROUP) in;
#endif

// This invocation's pixel p of images of `size`, its G-buffer surface g and g as vertex s seen
// from p's view; false where it has none.
bool restir_pixel(ivec3 size, out ivec3 p, out GSurface g, out PathVertex s) {
    if (!ray_pass_pixel(EFFECT_SHADOWS, size, p)) return false;
    g = gbuf_load(p);
    s = path_vertex_at_gbuffer(g, uint(p.z));
    return true;
}

// REFLECTIONS and above: RTReflections traces the specular lobes and shares their light (MIS).
bool restir_specular_traced(GSurface g) { return g.effect >= EFFECT_REFLECTIONS; }

#if RESTIR_HINTS
layout(r32ui) uniform uimage2DArray restir_hints;   // each pixel's visibility hints (restir_di.glsl)
uint restir_hints_at(ivec3 p) { return imageLoad(restir_hints, p).x; }
#else
uint restir_hints_at(ivec3 p) { return 0u; }
#endif
