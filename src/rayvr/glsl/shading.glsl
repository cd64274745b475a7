// Direct lighting of a surface point with the one BSDF, optionally with ray-traced visibility,
// shared by DirectLighting (no rays), RTShadows and the hits of RTReflections.
// Takes render-space points and directions (it does not need views.glsl); define SHADE_SHADOWS 1
// to trace shadow rays.
#pragma once
#include "scene.glsl"
#include "lights.glsl"
#include "bsdf.glsl"
#if SHADE_SHADOWS
#include "ray_query.glsl"
#endif

#ifndef LIGHT_SAMPLES
#define LIGHT_SAMPLES 1
#endif

// Mean over LIGHT_SAMPLES light samples of f(v, l) cos * Le / pdf, with visibility when SHADE_SHADOWS.
// p: render-space point; n: shading normal; ng: geometric normal; both facing v.
vec3 shade_direct(vec3 p, vec3 n, vec3 ng, vec3 v, BsdfParams m, inout Rng rng) {
    vec3 sum = vec3(0.0);
#if SCENE_HAS_PUNCTUAL_LIGHTS || SCENE_HAS_EMISSIVE_TRIANGLES
#if SHADE_SHADOWS
    vec3 origin = offset_ray_origin(p, ng);
#endif
    for (int k = 0; k < LIGHT_SAMPLES; ++k) {
        LightSample ls = sample_light(p, rng_next3(rng));
        if (!ls.valid || dot(ls.direction, ng) <= 0.0) continue;
        vec3 f = bsdf_eval(m, n, v, ls.direction);
        if (f.x + f.y + f.z <= 0.0) continue;
#if SHADE_SHADOWS
        if (trace_occluded(origin, ls.direction, ls.distance * (1.0 - 1e-4))) continue;
#endif
        sum += f * ls.weight;   // weight = radiance / pdf (lights.glsl)
    }
    sum *= 1.0 / float(LIGHT_SAMPLES);
#endif
    return sum;
}
