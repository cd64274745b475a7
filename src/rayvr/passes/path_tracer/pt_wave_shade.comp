// PathTracer, wavefront form (pt_wave.glsl): everything of a path but its rays, one stage a
// dispatch. From the G-buffer, stage 0 begins the paths of sample pt_sample (the first vertex's
// light sample and BSDF sample); from the camera, the trace kernel's stage 0 begins them with the
// camera ray and stage 1 here makes the first vertex. Each stage takes the answers
// pt_wave_trace.comp left, adds the light they bring and makes the next vertex's rays, with the
// megakernel's steps (path.glsl: pt_vertex, pt_shadow_answer, pt_ray_answer), so both forms draw
// the same random numbers and give the same paths. At the sample's last stage every pixel adds its
// path's share of the mean to the outputs (the first sample of the frame stores it) and keeps no
// state; with PTW_COMPACT a path adds it when it ends, and a path that goes on is queued for the
// next stage.
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
uniform int pt_stage;   // 0: the paths begin (from the G-buffer); k > 0: the answers to stage k - 1's rays
uniform int pt_sample;  // which of the frame's pt_samples
uniform bool pt_last;   // the sample's last stage: the paths' light goes to the outputs

const bool SPLIT = PT_LOBES != 0;

uint ptw_flags(PtRays r) {
    return PTW_ALIVE | (r.scattered ? PTW_SCATTERED : 0u) | (r.delta ? PTW_DELTA : 0u)
         | (r.transmitted ? PTW_TRANSMITTED : 0u);
}

#if PT_LOBES
void ptw_load_lobes(uint i, inout PtPath path) {
    path.first_diffuse = ptw_loadf(PTW_FIRST_DIFFUSE, i).xyz;
    path.first_total = ptw_loadf(PTW_FIRST_TOTAL, i).xyz;
    path.share = ptw_loadf(PTW_SHARE, i).xyz;
}
#endif

// What the next stages read: the whole path while it goes on; once it ended, its light and flags.
void ptw_store_state(uint i, PtPath path, PtRays r, uint flags, Rng rng) {
    ptw_storef(PTW_RADIANCE, i, path.radiance, r.pdf);
    ptw_storefu(PTW_POS, i, r.pos, flags);
#if PT_LOBES
    ptw_storef(PTW_FIRST_DIFFUSE, i, path.first_diffuse, 0.0);
    ptw_storef(PTW_FIRST_TOTAL, i, path.first_total, 0.0);
    ptw_storef(PTW_SHARE, i, path.share, 0.0);
#endif
    if ((flags & PTW_ALIVE) == 0u) return;
    ptw_storef(PTW_BETA, i, path.beta, r.cone_width);
    ptw_storefu(PTW_NEE, i, r.nee, rng_word(rng));
    ptw_storef(PTW_DIR, i, r.dir, r.cone_spread);
    ptw_storef(PTW_NG, i, r.ng, r.nee_dist);
    ptw_storefu(PTW_NEE_DIR, i, r.nee_dir, r.exit_instance);
#if PTW_HAS_MEDIUM
    ptw_storef(PTW_MEDIUM, i, path.medium, 0.0);
#endif
#if PT_LOBES
    ptw_storef(PTW_NEE_DIFFUSE, i, r.nee_diffuse, 0.0);
#endif
}

// A live path as the last stage stored it, its generator resumed from its word; what only the
// trace kernel needs (the rays' normal and shadow direction) is not read.
void ptw_load_state(uint i, ivec3 p, out PtPath path, out PtRays r, out uint flags, out Rng rng) {
    vec4 a = ptw_loadf(PTW_RADIANCE, i), b = ptw_loadf(PTW_BETA, i), d = ptw_loadf(PTW_DIR, i);
    uvec4 nee = ptw_load(PTW_NEE, i), pos = ptw_load(PTW_POS, i);
    path = pt_path_begin();
    r = pt_no_rays();
    path.radiance = a.xyz;
    path.beta = b.xyz;
    r.pdf = a.w;
    r.cone_width = b.w;
    r.nee = uintBitsToFloat(nee.xyz);
    rng = rng_resume(pt_rng(p, pt_sample), nee.w);
    r.pos = uintBitsToFloat(pos.xyz);
    flags = pos.w;
    r.dir = d.xyz;
    r.cone_spread = d.w;
    r.scattered = (flags & PTW_SCATTERED) != 0u;
    r.delta = (flags & PTW_DELTA) != 0u;
    r.transmitted = (flags & PTW_TRANSMITTED) != 0u;
#if PTW_HAS_MEDIUM
    path.medium = ptw_loadf(PTW_MEDIUM, i).xyz;
#endif
#if PT_LOBES
    ptw_load_lobes(i, path);
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
    uint i;
    ivec3 p;
    if (!ptw_path(i, p)) return;
    Rng rng;   // drawn only for a path that goes on
    PtPath path = pt_path_begin();
    PtRays r = pt_no_rays();
    uint flags = 0u;
    vec3 emitted = vec3(0.0);
    bool fresh = pt_stage == (PT_FROM_GBUFFER != 0 ? 0 : 1);   // `emitted` is made here, not loaded
#if PT_FROM_GBUFFER
    if (pt_stage == 0) {
#if SCENE_HAS_ALPHA_BLEND
        ptw_store(PTW_ANSWER, i, uvec4(0u));   // no BLEND ray traced yet
#endif
#if !PIXEL_LIST_INPUT
        if (gbuf_effect_at(p) == EFFECT_PATH_TRACED)   // other pixels: 0
#endif
        {
            GSurface g = gbuf_load(p);
            rng = pt_rng(p, pt_sample);
            emitted = g.emissive;
            if (pt_max_bounces > 0) {
                r = pt_vertex(path, path_vertex_at_gbuffer(g, uint(p.z)), 0, rng, SPLIT);
                flags = ptw_flags(r);
            }
        }
        if (!pt_last) ptw_storef(PTW_EMITTED, i, emitted, 0.0);
    } else
#endif
    {
        bool camera = PT_FROM_GBUFFER == 0 && pt_stage == 1;   // the camera ray's answer: the first vertex
        if (!camera) {
            flags = ptw_load(PTW_POS, i).w;
            if ((flags & PTW_ALIVE) == 0u && !pt_last) return;   // an ended path waits for the last stage
            if (pt_last) emitted = ptw_loadf(PTW_EMITTED, i).xyz;
        }
        if (!camera && (flags & PTW_ALIVE) == 0u) {
            path.radiance = ptw_loadf(PTW_RADIANCE, i).xyz;
#if PT_LOBES
            ptw_load_lobes(i, path);
#endif
        } else {
            uvec4 h = ptw_load(PTW_HIT, i), answer = ptw_load(PTW_ANSWER, i);
            Hit hit;
            hit.t = uintBitsToFloat(h.x);
            hit.barycentrics = uintBitsToFloat(h.yz);
            hit.instance = h.w;
            hit.primitive = answer.x;
            bool found = (answer.y & PTW_FOUND) != 0u;
            if (camera) {
                vec3 o;
                rng = pt_rng(p, pt_sample);
                pt_camera_ray(p, rng, o, r.dir);   // the camera kernel's ray, drawn again
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
                if (!pt_last) ptw_storef(PTW_EMITTED, i, emitted, 0.0);
            } else {
                ptw_load_state(i, p, path, r, flags, rng);
                int bounce = pt_stage - (PT_FROM_GBUFFER != 0 ? 1 : 2);   // whose rays were answered
                r.nee_dist = (answer.y & PTW_SHADOW) != 0u ? 0.0 : -1.0;
                pt_shadow_answer(path, r, (answer.y & PTW_OCCLUDED) != 0u, bounce, SPLIT);
                PathVertex s;
                if (r.scattered && pt_ray_answer(path, r, found, hit, bounce, s)) {
                    r = pt_vertex(path, s, bounce + 1, rng, SPLIT);
                    flags = ptw_flags(r);
                } else {
                    flags = 0u;
                }
            }
        }
    }
#if PTW_COMPACT
    if (pt_last || (flags & PTW_ALIVE) == 0u) {
        if (!fresh && !pt_last) emitted = ptw_loadf(PTW_EMITTED, i).xyz;
        ptw_output(p, path, flags, emitted);
    } else {
        ptw_store_state(i, path, r, flags, rng);
        ptq_push(i, r.dir);
    }
#else
    if (pt_last) ptw_output(p, path, flags, emitted);
    else ptw_store_state(i, path, r, flags, rng);
#endif
}
