// ReSTIR DI stage 1: each pixel's initial reservoir. RESTIR_CANDIDATES light samples from the light
// table (sample_light_id), one picked by resampled importance sampling with the target p_hat; its
// W = sum of weights / (M p_hat(pick)), M = RESTIR_CANDIDATES. With RESTIR_VISIBILITY_REUSE a
// shadow ray to the pick, and an occluded pick is dropped (W = 0), as the paper does: its
// neighbours then reuse only what this pixel sees. With RESTIR_TEMPORAL it also records the pixel's
// surface for next frame's reprojection, and with RESTIR_FUSED_TEMPORAL (no visibility ray here)
// does the temporal stage's reuse itself (restir_temporal.glsl): one kernel without a traversal,
// instead of two passes over the G-buffer.
#include "restir_stage.glsl"
#if RESTIR_VISIBILITY_REUSE
#include "ray_counters.glsl"
#endif
#if RESTIR_FUSED_TEMPORAL
#include "restir_temporal.glsl"
#endif

layout(rgba32ui) writeonly uniform uimage2DArray reservoirs_out;
#if RESTIR_TEMPORAL
layout(rgba32ui) writeonly uniform uimage2DArray surface_out;
#endif

void main() {
    ivec3 p;
    GSurface g;
    PathVertex s;
    if (!restir_pixel(imageSize(reservoirs_out), p, g, s)) return;
    bool specular_traced = restir_specular_traced(g);
#if RESTIR_TEMPORAL
    imageStore(surface_out, p, reservoir_surface_pack(gbuf_fetch_posW(p).w, g.n, gbuf_fetch_effect(p), s.v));
#endif
    uint hints = restir_hints_at(p);
    Rng rng = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT_RESTIR_CANDIDATES);
    ReservoirStream pick = stream_begin(rng_next(rng));
    for (int k = 0; k < RESTIR_CANDIDATES; ++k) {
        uvec2 id;
        LightSample ls = sample_light_id(s.pos, rng_next3(rng), id);
        // p_hat / source pdf, in any one measure: the sample's unshadowed contribution
        stream_add(pick, id, restir_contribution(s, specular_traced, ls, restir_hint(hints, id)), 0.0);
    }
    LightSample chosen = light_id_eval(pick.id, s.pos);
    pick.target = restir_target(s, specular_traced, chosen, restir_hint(hints, pick.id));
    Reservoir r = stream_reservoir(pick, float(RESTIR_CANDIDATES), float(RESTIR_CANDIDATES));
#if RESTIR_VISIBILITY_REUSE
    if (r.weight > 0.0) {
        vec3 origin = offset_ray_origin(s.pos, s.ng), dir;
        float tmax;
        shadow_ray(s.pos, origin, chosen, dir, tmax);
        if (!(trace_transmittance(origin, dir, tmax, path_vertex_skip(s, dir)) > 0.0)) {
            r.light = LIGHT_ID_NONE;
            r.weight = 0.0;
        }
    }
    ray_count_commit(uint(p.z));
#endif
#if RESTIR_FUSED_TEMPORAL
    r = restir_temporal_reuse(p, imageSize(reservoirs_out), g, s, hints, r, r.weight > 0.0 ? pick.target : 0.0);
#endif
    imageStore(reservoirs_out, p, reservoir_pack(r));
}
