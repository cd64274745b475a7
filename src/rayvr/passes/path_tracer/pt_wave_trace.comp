// PathTracer, wavefront form: the rays of every live path's vertex (pt_wave.glsl): its light
// sample's shadow ray, then its BSDF ray (or the camera ray), answered in the path's slot. Only
// traversal: no BSDF, light or material code, so no register of theirs.
#include "pt_pixel.glsl"
#include "pt_wave.glsl"

#if PIXEL_LIST_INPUT
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = RAY_GROUP_SIZE) in;
#endif

void main() {
    ivec3 p;
    if (!ptw_pixel(p)) return;
    uint i = ptw_slot();
    uvec4 pos = ptw_load(PTW_POS, i);
    uint flags = pos.w;
    if ((flags & PTW_ALIVE) == 0u) return;
    vec3 from = uintBitsToFloat(pos.xyz);
    uvec4 ng = ptw_load(PTW_NG, i);
    vec3 n = uintBitsToFloat(ng.xyz);
#if SCENE_HAS_ALPHA_BLEND   // the path's BLEND decisions go on where its last rays left them
    rq_blend_seed = ng.w;
    rq_blend_index = ptw_load(PTW_EMITTED, i).w;
    rq_blend_ray = ptw_load(PTW_ANSWER, i).z;
#endif
    uint answer = 0u;
    vec4 nee = ptw_loadf(PTW_NEE, i);
    if (nee.w >= 0.0 && trace_occluded(offset_ray_origin(from, n), ptw_loadf(PTW_NEE_DIR, i).xyz, nee.w))
        answer |= PTW_OCCLUDED;
    Hit hit;
    hit.t = 0.0;
    hit.barycentrics = vec2(0.0);
    hit.instance = 0u;
    hit.primitive = 0u;
    if ((flags & PTW_SCATTERED) != 0u) {
        vec3 o = (flags & PTW_CAMERA) != 0u ? from : offset_ray_origin(from, (flags & PTW_TRANSMITTED) != 0u ? -n : n);
        if (trace_closest(o, ptw_loadf(PTW_DIR, i).xyz, 1e30, hit)) answer |= PTW_FOUND;
    }
    ptw_store(PTW_HIT, i, uvec4(floatBitsToUint(hit.t), floatBitsToUint(hit.barycentrics), hit.instance));
    uint rays = 0u;
#if SCENE_HAS_ALPHA_BLEND
    rays = rq_blend_ray;
#endif
    ptw_store(PTW_ANSWER, i, uvec4(hit.primitive, answer, rays, 0u));
}
