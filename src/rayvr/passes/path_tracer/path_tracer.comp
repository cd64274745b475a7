// PathTracer: `pt_samples` paths per pixel for every view in one dispatch.
//   PT_FROM_GBUFFER 0: full screen from the camera (view_primary_ray, random sub-pixel offsets).
//   PT_FROM_GBUFFER 1: only PATH_TRACED pixels, starting at the G-buffer surface; with
//     PIXEL_LIST_INPUT 1 the dispatch is indirect over the compaction pass's pixel list.
#if PT_FROM_GBUFFER
#define GBUF_READER 1
#endif
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "path.glsl"
#include "ray_group.glsl"

#if PIXEL_LIST_INPUT
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = RAY_GROUP_SIZE) in;
#endif
layout(rgba32f) writeonly uniform image2DArray dst;
uniform int pt_samples;
uniform float pt_clamp;
uniform bool pt_pixel_jitter;

Rng pt_rng(ivec3 p, int sample_index) {
    return rng_init_sample(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT, uint(sample_index),
                           uint(pt_samples));
}

#if PT_FROM_GBUFFER
vec3 pt_pixel(ivec3 p) {
    GSurface g = gbuf_load(p);
    PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
    vec3 sum = vec3(0.0);
    for (int k = 0; k < pt_samples; ++k) {
        Rng rng = pt_rng(p, k);
        sum += pt_finite(g.emissive + pt_trace_from(s, rng), pt_clamp);
    }
    return sum / float(max(pt_samples, 1));
}
#else
vec3 pt_sample(ivec3 p, inout Rng rng) {
    // random sub-pixel positions (anti-aliasing once accumulated), else the centre moved by the
    // views' TAA jitter so the rays register with a jittered raster
    vec2 offset = pt_pixel_jitter ? rng_next2(rng) : vec2(0.5) + views[p.z].jitter.xy;
    vec3 o, d;
    view_primary_ray(uint(p.z), vec2(p.xy) + offset, o, d);
    Hit hit;
    if (!trace_closest(o, d, 1e30, hit)) return environment_radiance(d);
    float spread = view_pixel_spread(uint(p.z));
    SurfacePoint sp;
    MaterialParams mp;
    PathVertex s = path_vertex_at_hit(hit, d, hit.t * spread, spread, sp, mp);
    vec3 radiance = (sp.front_face || mp.double_sided) ? mp.emissive : vec3(0.0);
    return radiance + pt_trace_from(s, rng);
}

vec3 pt_pixel(ivec3 p) {
    vec3 sum = vec3(0.0);
    for (int k = 0; k < pt_samples; ++k) {
        Rng rng = pt_rng(p, k);
        sum += pt_finite(pt_sample(p, rng), pt_clamp);
    }
    return sum / float(max(pt_samples, 1));
}
#endif

void main() {
#if PIXEL_LIST_INPUT
    uint i = gl_GlobalInvocationID.x;
    if (i >= pixel_count) return;
    ivec3 p = pixel_list_unpack(pixel_items[i]);
#else
    ivec3 p = ray_group_pixel();
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
#if PT_FROM_GBUFFER
    if (gbuf_effect_at(p) != EFFECT_PATH_TRACED) {
        imageStore(dst, p, vec4(0.0));
        return;
    }
#endif
#endif
    imageStore(dst, p, vec4(pt_pixel(p), 1.0));
}
