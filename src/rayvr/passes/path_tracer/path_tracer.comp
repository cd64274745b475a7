// PathTracer: `pt_samples` paths per pixel for every view in one dispatch.
//   PT_FROM_GBUFFER 0: full screen from the camera (view_primary_ray, random sub-pixel offsets).
//   PT_FROM_GBUFFER 1: only PATH_TRACED pixels, starting at the G-buffer surface; with
//     PIXEL_LIST_INPUT 1 the dispatch is indirect over the compaction pass's pixel list.
//   PT_LOBES 1: also the first vertex's diffuse and specular parts (path.glsl pt_trace_parts) into
//     dst_diffuse / dst_specular, emission excluded (where a camera ray escapes, the background
//     is in dst_diffuse); dst is still their sum with the emission.
//   PT_SAMPLE_SLICES N > 0 (llvmpipe): a dispatch traces paths [pt_sample_first, + N) of the
//     pt_samples and adds their share of the mean to what the earlier dispatches of the frame
//     stored. llvmpipe ends all of an invocation's loops once they have run 65,535 iterations
//     together, silently (every traversal step is one), so many long paths in one invocation
//     would lose light; one path per invocation stays far below it.
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
#ifndef PT_SAMPLE_SLICES
#define PT_SAMPLE_SLICES 0
#endif
#if PT_SAMPLE_SLICES
#define PT_DST_ACCESS
uniform int pt_sample_first;   // this dispatch's first path
#define PT_K0 pt_sample_first
#define PT_K1 min(pt_sample_first + PT_SAMPLE_SLICES, pt_samples)
#else
#define PT_DST_ACCESS writeonly
#define PT_K0 0
#define PT_K1 pt_samples
#endif
layout(rgba32f) PT_DST_ACCESS uniform image2DArray dst;
uniform int pt_samples;
uniform float pt_clamp;
uniform bool pt_pixel_jitter;
#if PT_LOBES
layout(rgba16f) PT_DST_ACCESS uniform image2DArray dst_diffuse;
layout(rgba16f) PT_DST_ACCESS uniform image2DArray dst_specular;
#endif

// Sample `sample_index`'s generator; it also seeds the sample's alphaMode BLEND decisions.
Rng pt_rng(ivec3 p, int sample_index) {
    Rng r = rng_init_sample(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT, uint(sample_index),
                            uint(pt_samples));
    rq_blend_begin(r);
    return r;
}

#if PT_FROM_GBUFFER
vec3 pt_pixel(ivec3 p) {
    GSurface g = gbuf_load(p);
    PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
    vec3 sum = vec3(0.0);
    for (int k = PT_K0; k < PT_K1; ++k) {
        Rng rng = pt_rng(p, k);
        sum += pt_finite(g.emissive + pt_trace_from(s, rng), pt_clamp);
    }
    return sum / float(max(pt_samples, 1));
}
#else
// The first vertex of a camera path through pixel p and the radiance it emits towards the eye;
// false (`emitted` = the background) when the ray escapes.
bool pt_camera_vertex(ivec3 p, inout Rng rng, out PathVertex s, out vec3 emitted) {
    // random sub-pixel positions (anti-aliasing once accumulated), else the centre moved by the
    // views' TAA jitter so the rays register with a jittered raster
    vec2 offset = pt_pixel_jitter ? rng_next2(rng) : vec2(0.5) + views[p.z].jitter.xy;
    vec3 o, d;
    view_primary_ray(uint(p.z), vec2(p.xy) + offset, o, d);
    Hit hit;
    emitted = environment_radiance(d);
    if (!trace_closest(o, d, 1e30, hit)) return false;
    float spread = view_pixel_spread(uint(p.z));
    SurfacePoint sp;
    MaterialParams mp;
    s = path_vertex_at_hit(hit, d, hit.t * spread, spread, sp, mp);
    emitted = (sp.front_face || mp.double_sided) ? mp.emissive : vec3(0.0);
    return true;
}

vec3 pt_sample(ivec3 p, inout Rng rng) {
    PathVertex s;
    vec3 emitted;
    if (!pt_camera_vertex(p, rng, s, emitted)) return emitted;
    return emitted + pt_trace_from(s, rng);
}

vec3 pt_pixel(ivec3 p) {
    vec3 sum = vec3(0.0);
    for (int k = PT_K0; k < PT_K1; ++k) {
        Rng rng = pt_rng(p, k);
        sum += pt_finite(pt_sample(p, rng), pt_clamp);
    }
    return sum / float(max(pt_samples, 1));
}
#endif

#if PT_LOBES
// The mean of pt_samples paths as emission + diffuse + specular (a sample with a non-finite part
// is dropped whole and counted once; its parts clamped on their own); returns the sum.
vec3 pt_pixel_lobes(ivec3 p, out vec3 diffuse, out vec3 specular) {
    diffuse = vec3(0.0);
    specular = vec3(0.0);
    vec3 emitted = vec3(0.0);
#if PT_FROM_GBUFFER
    GSurface g = gbuf_load(p);
    PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
#endif
    for (int k = PT_K0; k < PT_K1; ++k) {
        Rng rng = pt_rng(p, k);
        vec3 d = vec3(0.0), r = vec3(0.0), e;
#if PT_FROM_GBUFFER
        e = g.emissive;
        pt_trace_parts(s, rng, true, d, r);
#else
        PathVertex s;
        if (pt_camera_vertex(p, rng, s, e)) {
            pt_trace_parts(s, rng, true, d, r);
        } else {   // the background travels as diffuse light
            d = e;
            e = vec3(0.0);
        }
#endif
        if (!(is_finite(e) && is_finite(d) && is_finite(r))) {
            nonfinite_count();
            continue;
        }
        emitted += pt_finite(e, pt_clamp);
        diffuse += pt_finite(d, pt_clamp);
        specular += pt_finite(r, pt_clamp);
    }
    float n = float(max(pt_samples, 1));
    diffuse /= n;
    specular /= n;
    return emitted / n + diffuse + specular;
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
#if PT_LOBES
        imageStore(dst_diffuse, p, vec4(0.0));
        imageStore(dst_specular, p, vec4(0.0));
#endif
        return;
    }
#endif
#endif
#if PT_LOBES
    vec3 diffuse, specular;
    vec3 c = pt_pixel_lobes(p, diffuse, specular);
#if PT_SAMPLE_SLICES
    if (pt_sample_first > 0) {   // the frame's earlier slices
        c += imageLoad(dst, p).rgb;
        diffuse += imageLoad(dst_diffuse, p).rgb;
        specular += imageLoad(dst_specular, p).rgb;
    }
#endif
    imageStore(dst, p, vec4(c, 1.0));
    imageStore(dst_diffuse, p, vec4(to_half_range(diffuse), 1.0));
    imageStore(dst_specular, p, vec4(to_half_range(specular), 1.0));
#else
    vec3 c = pt_pixel(p);
#if PT_SAMPLE_SLICES
    if (pt_sample_first > 0) c += imageLoad(dst, p).rgb;
#endif
    imageStore(dst, p, vec4(c, 1.0));
#endif
}
