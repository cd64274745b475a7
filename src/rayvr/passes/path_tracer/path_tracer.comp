// PathTracer: `pt_samples` paths per pixel for every view in one dispatch.
// The megakernel: every bounce's rays in one invocation (the wavefront form, pt_wave_*.comp,
// gives them dispatches of their own). pt_pixel.glsl has the modes (PT_FROM_GBUFFER,
// PIXEL_LIST_INPUT, PT_LOBES: emission excluded from dst_diffuse / dst_specular, where a camera ray
// escapes the background is in dst_diffuse; dst is still their sum with the emission).
//   PT_SAMPLE_SLICES N > 0 (llvmpipe): a dispatch traces paths [pt_sample_first, + N) of the
//     pt_samples and adds their share of the mean to what the earlier dispatches of the frame
//     stored. llvmpipe ends all of an invocation's loops once they have run 65,535 iterations
//     together, silently (every traversal step is one), so many long paths in one invocation
//     would lose light; one path per invocation stays far below it.
#include "pt_pixel.glsl"
#include "ray_counters.glsl"

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
#if PT_LOBES
layout(rgba16f) PT_DST_ACCESS uniform image2DArray dst_diffuse;
layout(rgba16f) PT_DST_ACCESS uniform image2DArray dst_specular;
#endif

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
    vec3 o, d;
    pt_camera_ray(p, rng, o, d);
    Hit hit;
    emitted = environment_radiance(d);
    if (!trace_closest(o, d, 1e30, hit)) return false;
    s = pt_camera_vertex_at(p, d, hit, emitted);
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
        if (!pt_sample_parts_finite(e, d, r)) continue;
        emitted += e;
        diffuse += d;
        specular += r;
    }
    float n = float(max(pt_samples, 1));
    diffuse /= n;
    specular /= n;
    return emitted / n + diffuse + specular;
}
#endif

void main() {
    ivec3 p;
#if PIXEL_LIST_INPUT
    if (!pixel_list_item(p)) return;
#else
    p = ray_group_pixel();
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
#if TRACE_DECISION
    if (decision_reconstructed(p)) return;   // the decision's fill gives it its source's light
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
    ray_count_commit(uint(p.z));
}
