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

#if SCENE_HAS_LIGHTS && SHADE_SHADOWS
// What light sample ls brings s (from `origin`, its offset ray origin) through its shadow ray:
// f cos * Le / pdf times the expected visibility through BLEND surfaces (not a coin toss per
// surface: a light behind a half-transparent leaf is half visible in every pixel), which is
// `visible` (0 without a ray: the sample brings nothing unshadowed).
vec3 shade_light_sample(PathVertex s, vec3 origin, LightSample ls, bool specular_traced, out float visible) {
    visible = 0.0;
    vec3 f = light_bsdf(s, ls, specular_traced);
    if (f.x + f.y + f.z <= 0.0) return vec3(0.0);
    vec3 c = f * ls.weight;   // weight = radiance / pdf (lights.glsl)
    if (c.x + c.y + c.z <= 0.0) return vec3(0.0);
    vec3 dir;
    float tmax;
    shadow_ray(s.pos, origin, ls, dir, tmax);
    visible = trace_transmittance(origin, dir, tmax, path_vertex_skip(s, dir));
    return visible > 0.0 ? c * visible : vec3(0.0);
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
#if SHADE_SHADOWS
        ls = sample_light(s.pos, rng_next3(rng));
        float visible;
        sum += shade_light_sample(s, origin, ls, specular_traced, visible);
#else
        sum += light_sample_unshadowed(s, rng_next3(rng), specular_traced, ls);
#endif
    }
    sum *= 1.0 / float(LIGHT_SAMPLES);
#endif
    return sum;
}

// -- one light sample shared by the views (RTShadows under a trace decision) ----------------------
// A light sample another pixel may take up, when it shows the same surface from another eye: which
// point of which light (lights.glsl `id`), 1 / the pdf it was drawn with in that light's measure,
// and the visibility its shadow ray found. The other pixel shades its own lobes towards that
// point over the same visibility: its glossy highlight is its own, its shadows the source's.
struct SharedLight { uvec2 id; float inv_pdf; float visible; };

uvec4 shared_light_pack(SharedLight l) { return uvec4(l.id, floatBitsToUint(l.inv_pdf), floatBitsToUint(l.visible)); }
SharedLight shared_light_unpack(uvec4 t) { return SharedLight(t.xy, uintBitsToFloat(t.z), uintBitsToFloat(t.w)); }

#if SHADE_SHADOWS
// shade_direct_mis(s, rng, specular_traced) with one light sample (LIGHT_SAMPLES 1), which
// `record` records.
vec3 shade_direct_shared(PathVertex s, inout Rng rng, bool specular_traced, out SharedLight record) {
    record = SharedLight(uvec2(0xFFFFFFFFu, 0u), 0.0, 0.0);
#if SCENE_HAS_LIGHTS
    uvec2 id;
    LightSample ls = sample_light_named(s.pos, rng_next3(rng), false, id);
    vec3 c = shade_light_sample(s, offset_ray_origin(s.pos, s.ng), ls, specular_traced, record.visible);
    // its weight over the same point's weight without its pdf (light_id_eval): 1 / that pdf
    float unweighted = max3(light_id_eval(id, s.pos).weight);
    record.id = id;
    record.inv_pdf = ls.valid && unweighted > 0.0 ? max3(ls.weight) / unweighted : 0.0;
    return c;
#else
    return vec3(0.0);
#endif
}
#endif

// The light that shared sample `l` brings vertex s: s's own f cos towards that point of that
// light and its geometry factor, the source's pdf and visibility. `specular_traced` as in
// shade_direct_mis: s's own rays sample its specular lobes, and the power heuristic weighs its
// own pdfs of the point (the source's, drawn a pixel footprint away, differs little).
vec3 shade_direct_from(PathVertex s, SharedLight l, bool specular_traced) {
#if SCENE_HAS_LIGHTS
    if (!(l.visible > 0.0) || !(l.inv_pdf > 0.0)) return vec3(0.0);
    LightSample ls = light_id_eval(l.id, s.pos);
    if (!ls.valid) return vec3(0.0);
    return light_bsdf(s, ls, specular_traced) * ls.weight * (l.inv_pdf * l.visible);
#else
    return vec3(0.0);
#endif
}

vec3 shade_direct(PathVertex s, inout Rng rng) { return shade_direct_mis(s, rng, false); }
