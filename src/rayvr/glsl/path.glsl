// Unidirectional path tracing from a path vertex: next-event estimation (lights.glsl) combined
// with BSDF sampling (bsdf.glsl) by the power heuristic, Russian roulette, delta lobes, and
// transmission: refraction through volumes (Beer-Lambert absorption inside them, the medium
// tracked by which face a refracted path enters or leaves) and thin-walled surfaces.
// Bounce k does NEE at vertex k and continues with a BSDF sample whose hit adds MIS-weighted
// emission, so max_bounces = 1 is complete direct light and 0 is emission only.
// Uniforms: pt_max_bounces, pt_rr_start.
#pragma once
#include "path_vertex.glsl"
#include "lights.glsl"
#include "ray_query.glsl"
#include "nonfinite.glsl"

uniform int pt_max_bounces;
uniform int pt_rr_start;

// Radiance arriving at the previous vertex from s (emission of s itself excluded), as the part
// s's diffuse lobe reflects and the rest (its specular lobes; with `split` false all of it is in
// `specular`, and the compiler drops the split). The diffuse part of what is found past s is
// the share of the first BSDF sample's weight that its diffuse lobe carries (f_d / pdf over
// f / pdf): what denoisers that demodulate the two lobes by their albedos need (SVGF).
// `medium`: the absorption of the medium the path travels through (0: air).
void pt_trace_parts(PathVertex s, inout Rng rng, const bool split, out vec3 diffuse, out vec3 specular) {
    vec3 radiance = vec3(0.0);
    vec3 beta = vec3(1.0);
    vec3 medium = vec3(0.0);
    vec3 first_diffuse = vec3(0.0);   // split: the diffuse part of the first vertex's light sample
    vec3 first_total = vec3(0.0);     // split: all the first vertex's light sample added
    vec3 share = vec3(0.0);           // split: the diffuse share of the first BSDF sample's weight
    for (int bounce = 0; bounce < pt_max_bounces; ++bounce) {
        // Everything that needs the BSDF comes first (the light sample's value, the BSDF sample,
        // the medium), so that it is dead while the rays are traced: fewer live registers there.
        vec3 nee = vec3(0.0);          // the light sample's contribution, if unoccluded
        vec3 nee_diffuse = vec3(0.0);  // split: its diffuse part
        vec3 nee_dir = vec3(0.0);
        float nee_dist = -1.0;         // < 0: no shadow ray
#if SCENE_HAS_LIGHTS
        LightSample ls = sample_light(s.pos, rng_next3(rng));
        if (ls.valid && dot(ls.direction, s.ng) > 0.0) {
            vec3 f = bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
            if (max3(f) > 0.0) {
                float w = ls.pdf > 0.0 ? power_heuristic(ls.pdf, bsdf_pdf(s.bsdf, s.n, s.v, ls.direction)) : 1.0;
                nee = beta * f * ls.weight * w;
                if (split && bounce == 0)
                    nee_diffuse = bsdf_eval_diffuse(s.bsdf, s.n, s.v, ls.direction) * ls.weight * w;
                nee_dir = ls.direction;
                nee_dist = ls.distance * (1.0 - 1e-4);
            }
        }
#endif
        BsdfSample bs;
        bool scattered = bsdf_sample(s.bsdf, s.n, s.v, rng_next3(rng), bs);
        // the sampled side must agree with the geometric surface (shading normals may not)
        float side = dot(bs.l, s.ng);
        if (scattered && (bs.transmitted ? side >= 0.0 : side <= 0.0)) scattered = false;
        if (scattered && split && bounce == 0 && !bs.delta && !bs.transmitted)
            share = clamp(bsdf_eval_diffuse(s.bsdf, s.n, s.v, bs.l) / (bs.pdf * max(bs.weight, vec3(1e-30))),
                          vec3(0.0), vec3(1.0));
        if (scattered && bs.transmitted && !s.bsdf.thin) medium = s.bsdf.inside ? vec3(0.0) : s.attenuation;
        if (nee_dist >= 0.0 && !trace_occluded(offset_ray_origin(s.pos, s.ng), nee_dir, nee_dist)) {
            radiance += nee;
            if (split && bounce == 0) first_diffuse = nee_diffuse;
        }
        if (split && bounce == 0) first_total = radiance;
        if (!scattered) break;
        beta *= bs.weight;
        if (!(max3(beta) > 0.0)) break;
        if (bounce >= pt_rr_start) {
            float q = clamp(max3(beta), 0.05, 1.0);
            if (rng_next(rng) >= q) break;
            beta /= q;
        }
        // The light sample above covers only the side of the surface that the geometric normal
        // faces, so a transmitted direction (below it) has no light-sampling strategy to share
        // with: its emission takes the whole weight, as a delta lobe's does.
        bool whole = bs.delta || bs.transmitted;
        Hit hit;
        if (!trace_closest(offset_ray_origin(s.pos, bs.transmitted ? -s.ng : s.ng), bs.l, 1e30, hit)) {
            float w = whole ? 1.0 : power_heuristic(bs.pdf, environment_light_pdf(bs.l));
            radiance += beta * environment_radiance(bs.l) * w;
            break;
        }
        if (max3(medium) > 0.0) beta *= exp(-medium * hit.t);
        float spread = cone_spread_after_bounce(s.cone_spread, bs.pdf, bs.delta);
        vec3 from = s.pos;
        SurfacePoint sp;
        MaterialParams mp;
#if SCENE_HAS_EMISSIVE_TRIANGLES
        if (bounce == pt_max_bounces - 1) {   // the path ends here: only the hit's emission counts
            sp = surface_at_cone(hit, bs.l, s.cone_width + hit.t * spread);
            mp = material_params_at(sp.material, sp.uv, sp.uv_lod);
        } else
#else
        if (bounce == pt_max_bounces - 1) break;
#endif
        s = path_vertex_at_hit(hit, bs.l, s.cone_width + hit.t * spread, spread, sp, mp);
#if SCENE_HAS_EMISSIVE_TRIANGLES
        if (max3(mp.emissive) > 0.0 && (sp.front_face || mp.double_sided)) {
            float w = whole ? 1.0 : power_heuristic(bs.pdf, emissive_light_pdf(sp, hit.instance, from));
            radiance += beta * mp.emissive * w;
        }
#endif
    }
    diffuse = split ? first_diffuse + share * (radiance - first_total) : vec3(0.0);
    specular = radiance - diffuse;
}

vec3 pt_trace_from(PathVertex s, inout Rng rng) {
    vec3 diffuse, specular;
    pt_trace_parts(s, rng, false, diffuse, specular);
    return specular;
}

// A sample's radiance made safe: NaN/Inf dropped (returns 0, counted: nonfinite.glsl), optional
// clamp (> 0) per channel.
vec3 pt_finite(vec3 c, float clamp_max) {
    c = nonfinite_scrub(c);
    return clamp_max > 0.0 ? min(c, vec3(clamp_max)) : c;
}
