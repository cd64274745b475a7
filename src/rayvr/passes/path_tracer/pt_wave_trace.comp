// PathTracer, wavefront form: the rays of every live path's vertex (pt_wave.glsl): its light
// sample's shadow ray, then its BSDF ray, answered in the path's slot. Built with PTW_CAMERA_RAYS 1
// it is mode "full"'s stage 0 instead: it makes and traces the camera rays, so no state precedes
// them. Only traversal (and the camera): no BSDF, light or material code, so no register of
// theirs; the camera's code is a program of its own for the same reason.
#include "pt_pixel.glsl"
#include "pt_wave.glsl"
#include "ray_counters.glsl"

#if PIXEL_LIST_INPUT
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = RAY_GROUP_SIZE) in;
#endif
uniform int pt_sample;

void main() {
    ivec3 p;
    if (!ptw_pixel(p)) return;
    uint i = ptw_slot();
    uint answer = 0u;
    vec3 o, d;
    bool closest = true;   // a BSDF or camera ray to trace (one call site: the traversal is inlined once)
#if PTW_CAMERA_RAYS
    Rng rng = pt_rng(p, pt_sample);   // also the BLEND decisions' seed
    pt_camera_ray(p, rng, o, d);
#else
    {
        uvec4 pos = ptw_load(PTW_POS, i);
        uint flags = pos.w;
        if ((flags & PTW_ALIVE) == 0u) return;
#if SCENE_HAS_ALPHA_BLEND   // the path's BLEND decisions go on where its last rays left them
        rq_blend_begin(pt_rng(p, pt_sample));
        rq_blend_ray = ptw_load(PTW_ANSWER, i).z;
#endif
        vec3 from = uintBitsToFloat(pos.xyz);
        vec4 ng = ptw_loadf(PTW_NG, i);
        if (ng.w >= 0.0) {
            answer |= PTW_SHADOW;
            if (trace_occluded(offset_ray_origin(from, ng.xyz), ptw_loadf(PTW_NEE_DIR, i).xyz, ng.w))
                answer |= PTW_OCCLUDED;
        }
        closest = (flags & PTW_SCATTERED) != 0u;
        if (closest) {
            o = offset_ray_origin(from, (flags & PTW_TRANSMITTED) != 0u ? -ng.xyz : ng.xyz);
            d = ptw_loadf(PTW_DIR, i).xyz;
        }
    }
#endif
    Hit hit;
    hit.t = 0.0;
    hit.barycentrics = vec2(0.0);
    hit.instance = 0u;
    hit.primitive = 0u;
    if (closest && trace_closest(o, d, 1e30, hit)) answer |= PTW_FOUND;
    ptw_store(PTW_HIT, i, uvec4(floatBitsToUint(hit.t), floatBitsToUint(hit.barycentrics), hit.instance));
    uint rays = 0u;
#if SCENE_HAS_ALPHA_BLEND
    rays = rq_blend_ray;
#endif
    ptw_store(PTW_ANSWER, i, uvec4(hit.primitive, answer, rays, 0u));
    ray_count_commit(uint(p.z));
}
