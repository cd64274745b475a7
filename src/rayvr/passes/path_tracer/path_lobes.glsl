// A path's first scattering vertex split by the BSDF's lobes, for denoisers that demodulate the
// diffuse and the specular light by their own albedos (rayvr.passes.SVGF). The same estimator as
// pt_trace_from (path.glsl): light sampling and BSDF sampling combined by the power heuristic,
// with each sample's weight f / pdf split into the diffuse part f_d / pdf and the rest (a
// mirror's delta lobe is all specular). The path beyond the first vertex is pt_trace_from's:
// the pass sets pt_max_bounces and pt_rr_start one lower while PT_LOBES is on.
#pragma once
#include "path.glsl"

uniform bool pt_lobes_first;   // max_bounces >= 1: the first vertex scatters at all

// Radiance that s reflects towards s.v (its own emission excluded), as the diffuse and specular
// lobes' parts.
void pt_trace_lobes(PathVertex s, inout Rng rng, out vec3 diffuse, out vec3 specular) {
    diffuse = vec3(0.0);
    specular = vec3(0.0);
    if (!pt_lobes_first) return;
    vec3 origin = offset_ray_origin(s.pos, s.ng);
#if SCENE_HAS_PUNCTUAL_LIGHTS || SCENE_HAS_EMISSIVE_TRIANGLES
    LightSample ls = sample_light(s.pos, rng_next3(rng));
    if (ls.valid && dot(ls.direction, s.ng) > 0.0) {
        vec3 fd = bsdf_eval_diffuse(s.bsdf, s.n, s.v, ls.direction);
        vec3 f = bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
        if (max3(f) > 0.0 && !trace_occluded(origin, ls.direction, ls.distance * (1.0 - 1e-4))) {
            float w = ls.pdf > 0.0 ? power_heuristic(ls.pdf, bsdf_pdf(s.bsdf, s.n, s.v, ls.direction)) : 1.0;
            diffuse += fd * ls.weight * w;
            specular += (f - fd) * ls.weight * w;
        }
    }
#endif
    BsdfSample bs;
    if (!bsdf_sample(s.bsdf, s.n, s.v, rng_next3(rng), bs) || dot(bs.l, s.ng) <= 0.0) return;
    vec3 weight_d = bs.delta ? vec3(0.0) : bsdf_eval_diffuse(s.bsdf, s.n, s.v, bs.l) / bs.pdf;
    vec3 weight_s = bs.weight - weight_d;
    vec3 li;
    Hit hit;
    if (!trace_closest(origin, bs.l, 1e30, hit)) {
        li = pt_background;
    } else {
        float spread = cone_spread_after_bounce(s.cone_spread, bs.pdf, bs.delta);
        vec3 from = s.pos;
        SurfacePoint sp;
        MaterialParams mp;
        PathVertex next = path_vertex_at_hit(hit, bs.l, s.cone_width + hit.t * spread, spread, sp, mp);
        li = pt_trace_from(next, rng);
#if SCENE_HAS_EMISSIVE_TRIANGLES
        if (max3(mp.emissive) > 0.0 && (sp.front_face || mp.double_sided)) {
            float w = bs.delta ? 1.0 : power_heuristic(bs.pdf, emissive_light_pdf(sp, hit.instance, from));
            li += mp.emissive * w;
        }
#endif
    }
    diffuse += weight_d * li;
    specular += weight_s * li;
}
