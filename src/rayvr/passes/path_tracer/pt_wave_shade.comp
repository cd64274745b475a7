// PathTracer, wavefront form (pt_wave.glsl): everything of a path but its rays, one stage a
// dispatch. Stage 0 begins the paths of sample pt_sample (the camera ray, or from the G-buffer
// the first vertex's light sample and BSDF sample); each later stage takes the answers
// pt_wave_trace.comp left, adds the light they bring and makes the next vertex's rays, with the
// megakernel's steps (path.glsl: pt_vertex, pt_shadow_answer, pt_ray_answer), so both forms draw
// the same random numbers and give the same paths. At the sample's last stage every pixel adds its
// path's share of the mean to the outputs (the first sample of the frame stores it).
#include "pt_pixel.glsl"
#include "pt_wave.glsl"

#if PIXEL_LIST_INPUT
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = RAY_GROUP_SIZE) in;
#endif
layout(rgba32f) uniform image2DArray dst;
#if PT_LOBES
layout(rgba16f) uniform image2DArray dst_diffuse;
layout(rgba16f) uniform image2DArray dst_specular;
#endif
uniform int pt_stage;   // 0: the paths begin; k > 0: the answers to stage k - 1's rays
uniform int pt_sample;  // which of the frame's pt_samples
uniform bool pt_last;   // the sample's last stage: the paths' light goes to the outputs

const bool SPLIT = PT_LOBES != 0;

uint ptw_flags(PtRays r) {
    return PTW_ALIVE | (r.scattered ? PTW_SCATTERED : 0u) | (r.delta ? PTW_DELTA : 0u)
         | (r.transmitted ? PTW_TRANSMITTED : 0u);
}

void ptw_store_state(uint i, PtPath path, PtRays r, uint flags, Rng rng, uint blend_seed) {
    ptw_storef(PTW_RADIANCE, i, path.radiance, r.pdf);
    ptw_storef(PTW_BETA, i, path.beta, r.cone_width);
    ptw_storef(PTW_MEDIUM, i, path.medium, r.cone_spread);
    ptw_storef(PTW_NEE, i, r.nee, r.nee_dist);
    ptw_storefu(PTW_POS, i, r.pos, flags);
    ptw_store(PTW_NG, i, uvec4(floatBitsToUint(r.ng), blend_seed));
    ptw_storefu(PTW_NEE_DIR, i, r.nee_dir, rng.state);
    ptw_storefu(PTW_DIR, i, r.dir, rng.group);
#if PT_LOBES
    ptw_storef(PTW_FIRST_DIFFUSE, i, path.first_diffuse, 0.0);
    ptw_storef(PTW_FIRST_TOTAL, i, path.first_total, 0.0);
    ptw_storef(PTW_SHARE, i, path.share, 0.0);
    ptw_storef(PTW_NEE_DIFFUSE, i, r.nee_diffuse, 0.0);
#endif
}

void ptw_load_state(uint i, out PtPath path, out PtRays r, out uint flags, inout Rng rng, out uint blend_seed) {
    vec4 a = ptw_loadf(PTW_RADIANCE, i), b = ptw_loadf(PTW_BETA, i), m = ptw_loadf(PTW_MEDIUM, i);
    vec4 nee = ptw_loadf(PTW_NEE, i);
    uvec4 pos = ptw_load(PTW_POS, i), ng = ptw_load(PTW_NG, i), nd = ptw_load(PTW_NEE_DIR, i), d = ptw_load(PTW_DIR, i);
    path = pt_path_begin();
    path.radiance = a.xyz;
    path.beta = b.xyz;
    path.medium = m.xyz;
    r.pdf = a.w;
    r.cone_width = b.w;
    r.cone_spread = m.w;
    r.nee = nee.xyz;
    r.nee_dist = nee.w;
    r.pos = uintBitsToFloat(pos.xyz);
    flags = pos.w;
    r.ng = uintBitsToFloat(ng.xyz);
    blend_seed = ng.w;
    r.nee_dir = uintBitsToFloat(nd.xyz);
    rng.state = nd.w;
    r.dir = uintBitsToFloat(d.xyz);
    rng.group = d.w;
    r.scattered = (flags & PTW_SCATTERED) != 0u;
    r.delta = (flags & PTW_DELTA) != 0u;
    r.transmitted = (flags & PTW_TRANSMITTED) != 0u;
    r.nee_diffuse = vec3(0.0);
#if PT_LOBES
    path.first_diffuse = ptw_loadf(PTW_FIRST_DIFFUSE, i).xyz;
    path.first_total = ptw_loadf(PTW_FIRST_TOTAL, i).xyz;
    path.share = ptw_loadf(PTW_SHARE, i).xyz;
    r.nee_diffuse = ptw_loadf(PTW_NEE_DIFFUSE, i).xyz;
#endif
}

// The pixel's share of this sample: what the path brought, as the megakernel sums it.
void ptw_output(ivec3 p, PtPath path, uint flags, vec3 emitted) {
    float share = 1.0 / float(max(pt_samples, 1));
    bool first = pt_sample == 0;
#if PT_LOBES
    vec3 d, s;
    if ((flags & PTW_ESCAPED) != 0u) {   // the background travels as diffuse light
        d = emitted;
        s = vec3(0.0);
        emitted = vec3(0.0);
    } else {
        pt_path_parts(path, true, d, s);
    }
    if (!pt_sample_parts_finite(emitted, d, s)) {
        emitted = vec3(0.0);
        d = vec3(0.0);
        s = vec3(0.0);
    }
    vec3 c = (emitted + d + s) * share;
    d *= share;
    s *= share;
    if (!first) {
        c += imageLoad(dst, p).rgb;
        d += imageLoad(dst_diffuse, p).rgb;
        s += imageLoad(dst_specular, p).rgb;
    }
    imageStore(dst, p, vec4(c, 1.0));
    imageStore(dst_diffuse, p, vec4(to_half_range(d), 1.0));
    imageStore(dst_specular, p, vec4(to_half_range(s), 1.0));
#else
    vec3 c = pt_finite(emitted + path.radiance, pt_clamp) * share;
    if (!first) c += imageLoad(dst, p).rgb;
    imageStore(dst, p, vec4(c, 1.0));
#endif
}

void main() {
    ivec3 p;
    if (!ptw_pixel(p)) return;
    uint i = ptw_slot();
    PtPath path;
    PtRays r;
    uint flags;
    vec3 emitted;
    Rng rng;
    uint blend_seed;
    if (pt_stage == 0) {
        rng = pt_rng(p, pt_sample);
        blend_seed = rng.state;   // the BLEND decisions of the path's rays (pt_wave_trace.comp)
        ptw_store(PTW_ANSWER, i, uvec4(0u));
        path = pt_path_begin();
        r = pt_no_rays();
        flags = 0u;
        emitted = vec3(0.0);
#if PT_FROM_GBUFFER
#if !PIXEL_LIST_INPUT
        if (gbuf_effect_at(p) == EFFECT_PATH_TRACED)   // other pixels: 0
#endif
        {
            GSurface g = gbuf_load(p);
            emitted = g.emissive;
            if (pt_max_bounces > 0) {
                r = pt_vertex(path, path_vertex_at_gbuffer(g, uint(p.z)), 0, rng, SPLIT);
                flags = ptw_flags(r);
            }
        }
#else
        vec3 o, d;
        pt_camera_ray(p, rng, o, d);
        r.pos = o;
        r.dir = d;
        flags = PTW_ALIVE | PTW_SCATTERED | PTW_CAMERA;
#endif
        ptw_store_state(i, path, r, flags, rng, blend_seed);
        ptw_storefu(PTW_EMITTED, i, emitted, rng.index);
    } else {
        flags = ptw_load(PTW_POS, i).w;
        uvec4 e = ptw_load(PTW_EMITTED, i);
        emitted = uintBitsToFloat(e.xyz);
        if ((flags & PTW_ALIVE) == 0u) {   // an ended path waits for the last stage with its light
            if (!pt_last) return;
            path = pt_path_begin();
            path.radiance = ptw_loadf(PTW_RADIANCE, i).xyz;
#if PT_LOBES
            path.first_diffuse = ptw_loadf(PTW_FIRST_DIFFUSE, i).xyz;
            path.first_total = ptw_loadf(PTW_FIRST_TOTAL, i).xyz;
            path.share = ptw_loadf(PTW_SHARE, i).xyz;
#endif
            ptw_output(p, path, flags, emitted);
            return;
        }
        rng.index = e.w;
        ptw_load_state(i, path, r, flags, rng, blend_seed);
        {
            uvec4 h = ptw_load(PTW_HIT, i), answer = ptw_load(PTW_ANSWER, i);
            Hit hit;
            hit.t = uintBitsToFloat(h.x);
            hit.barycentrics = uintBitsToFloat(h.yz);
            hit.instance = h.w;
            hit.primitive = answer.x;
            bool found = (answer.y & PTW_FOUND) != 0u;
            if ((flags & PTW_CAMERA) != 0u) {   // the camera ray's answer: the first vertex
                flags = 0u;
                if (!found) {
                    emitted = environment_radiance(r.dir);
                    flags = PTW_ESCAPED;
                } else {
                    PathVertex s = pt_camera_vertex_at(p, r.dir, hit, emitted);
                    if (pt_max_bounces > 0) {
                        r = pt_vertex(path, s, 0, rng, SPLIT);
                        flags = ptw_flags(r);
                    }
                }
                ptw_storefu(PTW_EMITTED, i, emitted, rng.index);
            } else {
                int bounce = pt_stage - (PT_FROM_GBUFFER != 0 ? 1 : 2);   // whose rays were answered
                pt_shadow_answer(path, r, (answer.y & PTW_OCCLUDED) != 0u, bounce, SPLIT);
                PathVertex s;
                if (r.scattered && pt_ray_answer(path, r, found, hit, bounce, s)) {
                    r = pt_vertex(path, s, bounce + 1, rng, SPLIT);
                    flags = ptw_flags(r);
                } else {
                    flags = 0u;
                }
            }
            ptw_store_state(i, path, r, flags, rng, blend_seed);
        }
    }
    if (pt_last) ptw_output(p, path, flags, emitted);
}
