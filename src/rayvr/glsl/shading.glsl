// Direct lighting of a path vertex with the one BSDF, optionally with ray-traced visibility,
// shared by DirectLighting (no rays), RTShadows and the hits of RTReflections.
// Takes render-space vertices (it does not need views.glsl); define SHADE_SHADOWS 1 to trace
// shadow rays.
#pragma once
#include "path_vertex.glsl"
#include "lights.glsl"
#if SHADE_SHADOWS
#include "ray_query.glsl"
#endif

#ifndef LIGHT_SAMPLES
#define LIGHT_SAMPLES 1
#endif

// f(v, l) cos at s towards light sample ls, zero when the light is below s's geometric horizon;
// with `specular_traced` (see shade_direct_mis) the specular lobes weighted by the power heuristic
// of ls.pdf against theirs (a punctual light, pdf 0, keeps them whole).
vec3 light_bsdf(PathVertex s, LightSample ls, bool specular_traced) {
    if (!ls.valid || dot(ls.direction, s.ng) <= 0.0) return vec3(0.0);
    if (specular_traced && ls.pdf > 0.0 && dot(s.n, ls.direction) > 0.0)
        return bsdf_eval_lobes(s.bsdf, s.n, s.v, ls.direction, BSDF_LOBES_DIFFUSE)
             + power_heuristic(ls.pdf, bsdf_pdf_specular(s.bsdf, s.n, s.v, ls.direction))
             * bsdf_eval_lobes(s.bsdf, s.n, s.v, ls.direction, BSDF_LOBES_SPECULAR);
    return bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
}

#if SCENE_HAS_LIGHTS
// One light sample at s from random numbers u, unshadowed: f(v, l) cos * Le / pdf, zero when the
// light is below s's geometric horizon or the BSDF reflects none of it; `ls` is the sample (its
// direction and distance make the shadow ray: shadow_ray in lights.glsl).
vec3 light_sample_unshadowed(PathVertex s, vec3 u, bool specular_traced, out LightSample ls) {
    ls = sample_light(s.pos, u);
    vec3 f = light_bsdf(s, ls, specular_traced);
    if (f.x + f.y + f.z <= 0.0) return vec3(0.0);
    return f * ls.weight;   // weight = radiance / pdf (lights.glsl)
}
#endif

// Mean over LIGHT_SAMPLES light samples of f(v, l) cos * Le / pdf at vertex s, with visibility
// when SHADE_SHADOWS. `specular_traced`: a ray pass also samples s's specular lobes
// (bsdf_sample_specular) and adds the lights its rays find (RTReflections, at the pixels whose
// effect is REFLECTIONS or above and at its reflective hits short of its bounce limit); the two
// share the specular lobes' light by the power heuristic, weight 1 together, so a near-mirror
// reflects an environment or a large emitter (which light sampling almost never finds in its
// narrow lobe) and a small emitter stays light-sampled. Punctual lights (pdf 0) stay here whole.
vec3 shade_direct_mis(PathVertex s, inout Rng rng, bool specular_traced) {
    vec3 sum = vec3(0.0);
#if SCENE_HAS_LIGHTS   // punctual, emissive or the environment (lights.glsl)
#if SHADE_SHADOWS
    vec3 origin = offset_ray_origin(s.pos, s.ng);
#endif
    for (int k = 0; k < LIGHT_SAMPLES; ++k) {
        LightSample ls;
        vec3 c = light_sample_unshadowed(s, rng_next3(rng), specular_traced, ls);
        if (c.x + c.y + c.z <= 0.0) continue;
#if SHADE_SHADOWS
        // the shadow ray's expected visibility through BLEND surfaces, not a coin toss per
        // surface: a light behind a half-transparent leaf is half visible in every pixel
        vec3 dir;
        float tmax;
        shadow_ray(s.pos, origin, ls, dir, tmax);
        float visible = trace_transmittance(origin, dir, tmax, path_vertex_skip(s, dir));
        if (visible <= 0.0) continue;
        c *= visible;
#endif
        sum += c;
    }
    sum *= 1.0 / float(LIGHT_SAMPLES);
#endif
    return sum;
}

vec3 shade_direct(PathVertex s, inout Rng rng) { return shade_direct_mis(s, rng, false); }
