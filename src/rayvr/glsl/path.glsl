// Unidirectional path tracing from a path vertex: next-event estimation (lights.glsl) combined
// with BSDF sampling (bsdf.glsl) by the power heuristic, Russian roulette, delta (mirror) lobes.
// Bounce k does NEE at vertex k and continues with a BSDF sample whose hit adds MIS-weighted
// emission, so max_bounces = 1 is complete direct light and 0 is emission only.
// Uniforms: pt_max_bounces, pt_rr_start, pt_background.
#pragma once
#include "path_vertex.glsl"
#include "lights.glsl"
#include "ray_query.glsl"

uniform int pt_max_bounces;
uniform int pt_rr_start;
uniform vec3 pt_background;

// Radiance arriving at the previous vertex from s (emission of s itself excluded).
vec3 pt_trace_from(PathVertex s, inout Rng rng) {
    vec3 radiance = vec3(0.0);
    vec3 beta = vec3(1.0);
    for (int bounce = 0; bounce < pt_max_bounces; ++bounce) {
        vec3 origin = offset_ray_origin(s.pos, s.ng);
#if SCENE_HAS_PUNCTUAL_LIGHTS || SCENE_HAS_EMISSIVE_TRIANGLES
        LightSample ls = sample_light(s.pos, rng_next3(rng));
        if (ls.valid && dot(ls.direction, s.ng) > 0.0) {
            vec3 f = bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
            if (max3(f) > 0.0 && !trace_occluded(origin, ls.direction, ls.distance * (1.0 - 1e-4))) {
                float w = ls.pdf > 0.0 ? power_heuristic(ls.pdf, bsdf_pdf(s.bsdf, s.n, s.v, ls.direction)) : 1.0;
                radiance += beta * f * ls.weight * w;
            }
        }
#endif
        BsdfSample bs;
        if (!bsdf_sample(s.bsdf, s.n, s.v, rng_next3(rng), bs)) break;
        if (dot(bs.l, s.ng) <= 0.0) break;   // below the geometric surface: no transmission
        beta *= bs.weight;
        if (!(max3(beta) > 0.0)) break;
        if (bounce >= pt_rr_start) {
            float q = clamp(max3(beta), 0.05, 1.0);
            if (rng_next(rng) >= q) break;
            beta /= q;
        }
        Hit hit;
        if (!trace_closest(origin, bs.l, 1e30, hit)) {
            radiance += beta * pt_background;
            break;
        }
        float spread = cone_spread_after_bounce(s.cone_spread, bs.pdf, bs.delta);
        vec3 from = s.pos;
        SurfacePoint sp;
        MaterialParams mp;
        s = path_vertex_at_hit(hit, bs.l, s.cone_width + hit.t * spread, spread, sp, mp);
#if SCENE_HAS_EMISSIVE_TRIANGLES
        if (max3(mp.emissive) > 0.0 && (sp.front_face || mp.double_sided)) {
            float w = bs.delta ? 1.0 : power_heuristic(bs.pdf, emissive_light_pdf(sp, hit.instance, from));
            radiance += beta * mp.emissive * w;
        }
#endif
    }
    return radiance;
}

// A sample's radiance made safe: NaN/Inf dropped (returns 0), optional clamp (> 0) per channel.
vec3 pt_finite(vec3 c, float clamp_max) {
    c = finite_or_zero(c);
    return clamp_max > 0.0 ? min(c, vec3(clamp_max)) : c;
}
