// PathTracer, wavefront form: the rays of every live path's vertex (pt_wave.glsl): its light
// sample's shadow ray, then its BSDF ray, answered in the path's slot. Built with PTW_CAMERA_RAYS 1
// it is mode "full"'s stage 0 instead: it makes and traces the camera rays, so no state precedes
// them. Only traversal (and the camera): no BSDF, light or material code, so no register of
// theirs; the camera's code is a program of its own for the same reason.
//   PTW_PERSISTENT 1 (with PTW_COMPACT, GL_ARB_shader_ballot): a fixed set of workgroups takes the
//   queue's paths (Aila & Laine 2009's persistent threads): a subgroup's lanes whose rays are done
//   take the next paths (one atomic per subgroup) whenever fewer than PTW_REFILL_BELOW of them are
//   still tracing, so a warp does not idle behind its longest ray; the rays interleave as
//   ray_query.glsl's steps. The same rays and answers as one invocation per path.
#include "pt_pixel.glsl"
#include "pt_wave.glsl"
#include "ray_counters.glsl"

#if PIXEL_LIST_INPUT && !PTW_PERSISTENT
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = RAY_GROUP_SIZE) in;
#endif
uniform int pt_sample;

// Path i's BLEND decisions (pixel p) resume where its last rays left them.
void ptw_blend_resume(uint i, ivec3 p) {
#if SCENE_HAS_ALPHA_BLEND
    rq_blend_begin(pt_rng(p, pt_sample));
    rq_blend_ray = ptw_load(PTW_ANSWER, i).z;
#endif
}

// Path i's shadow ray (so, sd, stmax, the instance it skips): false when its vertex has none.
bool ptw_shadow_ray(uint i, out vec3 so, out vec3 sd, out float stmax, out uint skip) {
    vec4 ng = ptw_loadf(PTW_NG, i);
    so = offset_ray_origin(uintBitsToFloat(ptw_load(PTW_POS, i).xyz), ng.xyz);
    uvec4 nee_dir = ptw_load(PTW_NEE_DIR, i);
    sd = uintBitsToFloat(nee_dir.xyz);
    skip = nee_dir.w;
    stmax = ng.w;
    return ng.w >= 0.0;
}

// The instance path i's BSDF ray skips: its vertex's exit instance unless the ray is transmitted.
uint ptw_bsdf_skip(uint i, uint flags) {
    return (flags & PTW_TRANSMITTED) != 0u ? SCENE_NO_INSTANCE : ptw_load(PTW_NEE_DIR, i).w;
}

// Path i's BSDF ray (o, d) from its state flags: false when it scattered none. Loaded after its
// shadow ray is traced, so that o and d take no registers during that traversal.
bool ptw_bsdf_ray(uint i, uint flags, out vec3 o, out vec3 d) {
    vec3 ng = ptw_loadf(PTW_NG, i).xyz;
    o = offset_ray_origin(uintBitsToFloat(ptw_load(PTW_POS, i).xyz), (flags & PTW_TRANSMITTED) != 0u ? -ng : ng);
    d = ptw_loadf(PTW_DIR, i).xyz;
    return (flags & PTW_SCATTERED) != 0u;
}

// Store path i's answers: the BSDF (or camera) ray's hit, PTW_FOUND | PTW_OCCLUDED | PTW_SHADOW.
void ptw_answer(uint i, bool found, Hit hit, uint answer) {
    if (!found) {
        hit.t = 0.0;
        hit.barycentrics = vec2(0.0);
        hit.instance = 0u;
        hit.primitive = 0u;
    }
    ptw_store(PTW_HIT, i, uvec4(floatBitsToUint(hit.t), floatBitsToUint(hit.barycentrics), hit.instance));
    uint rays = 0u;
#if SCENE_HAS_ALPHA_BLEND
    rays = rq_blend_ray;
#endif
    ptw_store(PTW_ANSWER, i, uvec4(hit.primitive, answer | (found ? PTW_FOUND : 0u), rays, 0u));
}

#if PTW_PERSISTENT
#ifndef PTW_REFILL_BELOW
#define PTW_REFILL_BELOW 16
#endif
uint lanes(bool b) { uvec2 m = unpackUint2x32(ballotARB(b)); return uint(bitCount(m.x) + bitCount(m.y)); }

void main() {
    uint total = ptq_args[ptq_in].w;
    bool tracing = false, drained = false;
    uint i = 0u, answer = 0u;
    bool shadow_ray = false, then_closest = false;   // the ray in flight is the shadow ray; the BSDF ray follows
    vec3 o = vec3(0.0), d = vec3(0.0);
    uint skip = SCENE_NO_INSTANCE, bsdf_skip = SCENE_NO_INSTANCE;
    while (true) {
        if (!drained) {
            bool need = !tracing;
            uvec2 m = unpackUint2x32(ballotARB(need));
            uint n = uint(bitCount(m.x) + bitCount(m.y));
            if (n > 0u) {
                uint leader = m.x != 0u ? uint(findLSB(m.x)) : 32u + uint(findLSB(m.y));
                uint first = 0u;
                if (gl_SubGroupInvocationARB == leader) first = atomicAdd(ptq_args[2].x, n);
                first = readInvocationARB(first, leader);
                uvec2 lt = unpackUint2x32(gl_SubGroupLtMaskARB);
                uint j = first + uint(bitCount(m.x & lt.x) + bitCount(m.y & lt.y));
                drained = first + n >= total;
                if (need && j < total) {
                    i = ptq_items[ptq_in * pt_wave_paths + j];
                    vec3 so, sd;
                    float stmax;
                    ptw_blend_resume(i, ptw_slot_pixel(i));
                    shadow_ray = ptw_shadow_ray(i, so, sd, stmax, skip);
                    uint flags = ptw_load(PTW_POS, i).w;
                    bool closest = ptw_bsdf_ray(i, flags, o, d);
                    bsdf_skip = ptw_bsdf_skip(i, flags);
                    answer = shadow_ray ? PTW_SHADOW : 0u;
                    then_closest = shadow_ray && closest;
                    if (shadow_ray) rq_begin(so, sd, stmax, true, skip);
                    else if (closest) rq_begin(o, d, 1e30, false, bsdf_skip);
                    tracing = (shadow_ray || closest) && !rq_done;
                    if (!tracing) {   // no rays, or no instances
                        ptw_answer(i, false, rq_hit, answer);
                        ray_count_commit(uint(ptw_slot_pixel(i).z));
                    }
                }
            }
        }
        if (!anyInvocationARB(tracing)) break;
        do {
            if (tracing && !rq_step()) {
                if (shadow_ray && rq_found) answer |= PTW_OCCLUDED;
                if (then_closest) {   // the shadow ray is answered: now the BSDF ray
                    shadow_ray = then_closest = false;
                    rq_begin(o, d, 1e30, false, bsdf_skip);
                } else {
                    ptw_answer(i, !shadow_ray && rq_found, rq_hit, answer);
                    ray_count_commit(uint(ptw_slot_pixel(i).z));   // this path's rays, to its view
                    tracing = false;
                }
            }
        } while (lanes(tracing) >= (drained ? 1u : uint(PTW_REFILL_BELOW)));
    }
}

#else
void main() {
    uint i;
    ivec3 p;
    if (!ptw_path(i, p)) return;
    uint answer = 0u;
    vec3 o, d;
    uint skip = SCENE_NO_INSTANCE;   // a camera ray skips nothing
    bool closest = true;   // a BSDF or camera ray to trace (one call site: the traversal is inlined once)
#if PTW_CAMERA_RAYS
    Rng rng = pt_rng(p, pt_sample);   // also the BLEND decisions' seed
    pt_camera_ray(p, rng, o, d);
#else
    uint flags = ptw_load(PTW_POS, i).w;
    if ((flags & PTW_ALIVE) == 0u) return;
    ptw_blend_resume(i, p);
    {
        vec3 so, sd;
        float stmax;
        uint shadow_skip;
        if (ptw_shadow_ray(i, so, sd, stmax, shadow_skip))
            answer = PTW_SHADOW | (trace_occluded(so, sd, stmax, shadow_skip) ? PTW_OCCLUDED : 0u);
    }
    closest = ptw_bsdf_ray(i, flags, o, d);
    skip = ptw_bsdf_skip(i, flags);
#endif
    Hit hit;
    bool found = closest && trace_closest(o, d, 1e30, skip, hit);
    ptw_answer(i, found, hit, answer);
    ray_count_commit(uint(p.z));
}
#endif
