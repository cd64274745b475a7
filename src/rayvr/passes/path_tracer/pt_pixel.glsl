// What the path tracer's kernels share about a pixel (path_tracer.comp, the megakernel, and the
// wavefront's pt_wave_shade.comp): which pixel an invocation serves, its paths' generators, the
// camera ray, and the output images with their accumulation over a frame's dispatches.
//   PT_FROM_GBUFFER 0: full screen from the camera; 1: only PATH_TRACED pixels, from the G-buffer
//     surface (PIXEL_LIST_INPUT 1: the invocations run over the compaction pass's pixel list).
//   PT_LOBES 1: also the first vertex's diffuse and specular parts, in dst_diffuse / dst_specular.
#pragma once
#if PT_FROM_GBUFFER
#define GBUF_READER 1
#endif
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "path.glsl"
#include "ray_group.glsl"

uniform int pt_samples;
uniform float pt_clamp;
uniform bool pt_pixel_jitter;

// Sample `sample_index`'s generator; it also seeds the sample's alphaMode BLEND decisions.
Rng pt_rng(ivec3 p, int sample_index) {
    Rng r = rng_init_sample(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT, uint(sample_index),
                            uint(pt_samples));
    rq_blend_begin(r);
    return r;
}

// The camera ray through pixel p: random sub-pixel positions (anti-aliasing once accumulated),
// else the centre moved by the views' TAA jitter so the rays register with a jittered raster.
void pt_camera_ray(ivec3 p, inout Rng rng, out vec3 o, out vec3 d) {
    vec2 offset = pt_pixel_jitter ? rng_next2(rng) : vec2(0.5) + views[p.z].jitter.xy;
    view_primary_ray(uint(p.z), vec2(p.xy) + offset, o, d);
}

// The first vertex of a camera ray (o, d) that hit `hit`, and the radiance it emits towards the eye.
PathVertex pt_camera_vertex_at(ivec3 p, vec3 d, Hit hit, out vec3 emitted) {
    float spread = view_pixel_spread(uint(p.z));
    SurfacePoint sp;
    MaterialParams mp;
    PathVertex s = path_vertex_at_hit(hit, d, hit.t * spread, spread, sp, mp);
    emitted = (sp.front_face || mp.double_sided) ? mp.emissive : vec3(0.0);
    return s;
}

// One sample's parts made safe for a pixel's mean: each clamped (pt_clamp > 0) on its own, or
// false (counted once, nonfinite.glsl) when any is NaN or Inf: the sample is dropped whole.
bool pt_sample_parts_finite(inout vec3 emitted, inout vec3 diffuse, inout vec3 specular) {
    if (!(is_finite(emitted) && is_finite(diffuse) && is_finite(specular))) {
        nonfinite_count();
        return false;
    }
    emitted = pt_finite(emitted, pt_clamp);
    diffuse = pt_finite(diffuse, pt_clamp);
    specular = pt_finite(specular, pt_clamp);
    return true;
}
