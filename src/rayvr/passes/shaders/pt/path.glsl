// Unidirectional path tracing from a surface point: next-event estimation (lights.glsl) combined
// with BSDF sampling (bsdf.glsl) by the power heuristic, Russian roulette, delta (mirror) lobes.
// Bounce k does NEE at vertex k and continues with a BSDF sample whose hit adds MIS-weighted
// emission, so max_bounces = 1 is complete direct light and 0 is emission only.
// Uniforms: pt_max_bounces, pt_rr_start, pt_background.
#pragma once
#include "scene.glsl"
#include "lights.glsl"
#include "bsdf.glsl"
#include "ray_query.glsl"

uniform int pt_max_bounces;
uniform int pt_rr_start;
uniform vec3 pt_background;

struct PathVertex {
    vec3 pos;        // render space
    vec3 n;          // shading normal facing v
    vec3 ng;         // geometric normal facing v
    vec3 v;          // towards the previous vertex
    BsdfParams m;
    float cone_width;    // the path's ray cone at pos (texture level of detail)
    float cone_spread;   // and its spread angle
};

float pt_max3(vec3 c) { return max(c.x, max(c.y, c.z)); }
float pt_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// Probability of sampling the specular lobe: its Fresnel-weighted share of the albedo.
float pt_specular_probability(BsdfParams m, vec3 n, vec3 v) {
    float ls = pt_luminance(fresnel_schlick(bsdf_f0(m), clamp(dot(n, v), 0.0, 1.0)));
    float ld = pt_luminance(bsdf_diffuse_albedo(m));
    if (ld <= 0.0) return 1.0;
    return clamp(ls / max(ls + ld, 1e-8), 0.05, 0.95);
}

// Solid-angle pdf of pt_sample_bsdf choosing l (non-delta part), for MIS.
float pt_bsdf_pdf(BsdfParams m, vec3 n, vec3 v, vec3 l, float p_spec) {
    float n_l = dot(n, l);
    if (n_l <= 0.0) return 0.0;
    return p_spec * bsdf_pdf_specular(m, n, v, l) + (1.0 - p_spec) * n_l / RAYVR_PI;
}

// One BSDF sample: direction l, weight f cos / pdf, pdf (0 and delta = true for a mirror bounce).
bool pt_sample_bsdf(BsdfParams m, vec3 n, vec3 v, float p_spec, inout Rng rng,
                    out vec3 l, out vec3 weight, out float pdf, out bool delta) {
    vec2 u = rng_next2(rng);
    float pick = rng_next(rng);
    delta = false;
    pdf = 0.0;
    weight = vec3(0.0);
    if (pick < p_spec) {
        bool valid;
        vec3 w = bsdf_sample_specular(m, n, v, u, l, valid);
        if (!valid) return false;
        if (bsdf_is_mirror(m)) {
            delta = true;
            weight = w / p_spec;
            return true;
        }
    } else {
        bsdf_sample_diffuse(m, n, u, l);
    }
    pdf = pt_bsdf_pdf(m, n, v, l, p_spec);
    if (!(pdf > 0.0)) return false;
    weight = bsdf_eval(m, n, v, l) / pdf;
    return true;
}

// Radiance arriving at the previous vertex from s (emission of s itself excluded).
vec3 pt_trace_from(PathVertex s, inout Rng rng) {
    vec3 radiance = vec3(0.0);
    vec3 beta = vec3(1.0);
    for (int bounce = 0; bounce < pt_max_bounces; ++bounce) {
        float p_spec = pt_specular_probability(s.m, s.n, s.v);
        vec3 origin = offset_ray_origin(s.pos, s.ng);
#if SCENE_HAS_PUNCTUAL_LIGHTS || SCENE_HAS_EMISSIVE_TRIANGLES
        LightSample ls = sample_light(s.pos, rng_next3(rng));
        if (ls.valid && dot(ls.direction, s.ng) > 0.0) {
            vec3 f = bsdf_eval(s.m, s.n, s.v, ls.direction);
            if (pt_max3(f) > 0.0 && !trace_occluded(origin, ls.direction, ls.distance * (1.0 - 1e-4))) {
                float w = ls.pdf > 0.0 ? power_heuristic(ls.pdf, pt_bsdf_pdf(s.m, s.n, s.v, ls.direction, p_spec)) : 1.0;
                radiance += beta * f * ls.weight * w;
            }
        }
#endif
        vec3 l, weight;
        float pdf;
        bool delta;
        if (!pt_sample_bsdf(s.m, s.n, s.v, p_spec, rng, l, weight, pdf, delta)) break;
        if (dot(l, s.ng) <= 0.0) break;   // below the geometric surface: no transmission
        beta *= weight;
        if (!(pt_max3(beta) > 0.0)) break;
        if (bounce >= pt_rr_start) {
            float q = clamp(pt_max3(beta), 0.05, 1.0);
            if (rng_next(rng) >= q) break;
            beta /= q;
        }
        Hit hit;
        if (!trace_closest(origin, l, 1e30, hit)) {
            radiance += beta * pt_background;
            break;
        }
        s.cone_spread = cone_spread_after_bounce(s.cone_spread, pdf, delta);
        s.cone_width += hit.t * s.cone_spread;
        SurfacePoint sp = surface_at_cone(hit, l, s.cone_width);
        MaterialParams mp = material_params_at(sp.material, sp.uv, sp.uv_lod);
#if SCENE_HAS_EMISSIVE_TRIANGLES
        if (pt_max3(mp.emissive) > 0.0 && (sp.front_face || mp.double_sided)) {
            float w = delta ? 1.0 : power_heuristic(pdf, emissive_light_pdf(sp, hit.instance, s.pos));
            radiance += beta * mp.emissive * w;
        }
#endif
        s.pos = sp.position;
        s.n = sp.normal;
        s.ng = sp.geometric_normal;
        s.v = -l;
        s.m = bsdf_params(mp.base_color, mp.metallic, mp.roughness);
    }
    return radiance;
}

// A sample's radiance made safe: NaN/Inf dropped (returns 0), optional clamp (> 0) per channel.
vec3 pt_finite(vec3 c, float clamp_max) {
    if (any(isnan(c)) || any(isinf(c))) return vec3(0.0);
    return clamp_max > 0.0 ? min(c, vec3(clamp_max)) : c;
}
