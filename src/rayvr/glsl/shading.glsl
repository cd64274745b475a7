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

// f(v, l) cos * Le / pdf of one light sample at vertex s, with visibility when SHADE_SHADOWS (from
// `origin`, s's offset position). `specular_traced`: a ray pass also samples s's specular lobes
// (bsdf_sample_specular) and adds the lights its rays find (RTReflections, at the pixels whose
// effect is REFLECTIONS or above and at its reflective hits short of its bounce limit); the two
// share the specular lobes' light by the power heuristic, weight 1 together, so a near-mirror
// reflects an environment or a large emitter (which light sampling almost never finds in its
// narrow lobe) and a small emitter stays light-sampled. Punctual lights (pdf 0) stay here whole.
vec3 shade_light(PathVertex s, LightSample ls, vec3 origin, bool specular_traced) {
    if (!ls.valid || dot(ls.direction, s.ng) <= 0.0) return vec3(0.0);
    vec3 f;
    if (specular_traced && ls.pdf > 0.0 && dot(s.n, ls.direction) > 0.0)
        f = bsdf_eval_diffuse(s.bsdf, s.n, s.v, ls.direction)
          + power_heuristic(ls.pdf, bsdf_pdf_specular(s.bsdf, s.n, s.v, ls.direction))
          * bsdf_eval_reflection(s.bsdf, s.n, s.v, ls.direction);
    else
        f = bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
    if (f.x + f.y + f.z <= 0.0) return vec3(0.0);
#if SHADE_SHADOWS
    // the shadow ray's expected visibility through BLEND surfaces, not a coin toss per surface: a
    // light behind a half-transparent leaf is half visible in every pixel
    float visible = trace_transmittance(origin, ls.direction, ls.distance * (1.0 - 1e-4));
    if (visible <= 0.0) return vec3(0.0);
    f *= visible;
#endif
    return f * ls.weight;   // weight = radiance / pdf (lights.glsl)
}

// The direct light at vertex s (see shade_light). In a scene of at most LOCAL_PUNCTUAL_MAX
// punctual lights every one of them is evaluated, each with its own shadow ray where it lights s
// unshadowed: no selection noise (tauray/test.glb's spot cone, where the sun's share of the one
// sample left a black speckle); the emitters and the environment, if any, are then the mean of
// LIGHT_SAMPLES samples of the light table, whose punctual draws count 0 (unbiased: those lights
// are already summed). Otherwise all lights are the mean of LIGHT_SAMPLES table samples.
// One loop with one shade_light call site: a second inlined shadow-ray traversal cost the H200's
// shadow pass 1.5x and the reflection pass 2.8x (tauray, 2x1440x1600).
vec3 shade_direct_mis(PathVertex s, inout Rng rng, bool specular_traced) {
    vec3 sum = vec3(0.0);
#if SCENE_HAS_LIGHTS   // punctual, emissive or the environment (lights.glsl)
    vec3 origin = vec3(0.0);
#if SHADE_SHADOWS
    origin = offset_ray_origin(s.pos, s.ng);
#endif
    int every = 0;   // punctual lights evaluated one by one
#if SCENE_HAS_PUNCTUAL_LIGHTS
    uint np = punctual_light_count();
    if (np <= uint(LOCAL_PUNCTUAL_MAX)) every = int(np);
#endif
    bool others = SCENE_HAS_EMISSIVE_TRIANGLES != 0 || SCENE_HAS_ENVIRONMENT != 0;
    int samples = every == 0 || others ? LIGHT_SAMPLES : 0;
    for (int k = 0; k < every + samples; ++k) {
        LightSample ls = no_light_sample();
        float scale = 1.0;
        if (k < every) {
#if SCENE_HAS_PUNCTUAL_LIGHTS
            ls = eval_punctual_light(uint(k), s.pos);
#endif
        } else {
            ls = sample_light(s.pos, rng_next3(rng));
            if (every > 0 && ls.pdf == 0.0) ls.valid = false;   // a punctual light: summed already
            scale = 1.0 / float(LIGHT_SAMPLES);
        }
        sum += scale * shade_light(s, ls, origin, specular_traced);
    }
#endif
    return sum;
}

vec3 shade_direct(PathVertex s, inout Rng rng) { return shade_direct_mis(s, rng, false); }
