// Mirror, glossy and refracted light for the pixels whose effect is REFLECTIONS or above (those on
// the reflection list, dispatched indirectly, or with PIXELS_2D the whole image in tiles): sample
// the BSDF's specular lobes (GGX VNDF reflection, and for transmissive materials refraction or a
// thin wall's pass-through; exact deltas at roughness 0), trace, shade the hit with emission and
// shadowed direct light, continue up to MAX_BOUNCES through reflective hits (absorbing inside
// volumes), REFLECTION_BOUNCES of them reflected (the others transmitted). Light a rough lobe's ray
// finds (emitters, the environment) and the light sample of the vertex it left share it by the
// power heuristic (shading.glsl shade_direct_mis). Output: that radiance weighted by the specular
// lobes, which the composite adds to the direct light (the diffuse part is the direct-light
// passes'). Each hit adds the probes' indirect diffuse light, and a path whose reflections end on a
// reflective surface their glossy fallback: with PROBE_RECORDS (the graph's way) this kernel only
// records what the lookups need (glsl/probe_records.glsl: one record per view and bounce, an empty
// one past the path's end) and rt_reflections_probes.comp, dispatched after it over the same
// pixels, looks them up and adds them (the lookup's registers here would cost the traversal its
// occupancy: several times slower); with PROBE_GI instead they are looked up in this kernel (only
// tests compile that, as the reference).
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "shading.glsl"
#include "probe_records.glsl"   // and probe_gi.glsl
#include "nonfinite.glsl"
#include "ray_counters.glsl"

#if PIXELS_2D   // every pixel of the image; those whose effect needs no such rays leave at once
layout(local_size_x = RAY_GROUP_SIZE) in;
#else           // the pixels on the list
layout(local_size_x = PIXEL_LIST_GROUP) in;
#endif
layout(rgba16f) writeonly uniform image2DArray dst;
#ifndef PROBE_RECORDS
#define PROBE_RECORDS 0
#endif
#ifndef REFLECTION_BOUNCES
#define REFLECTION_BOUNCES MAX_BOUNCES
#endif
#if PROBE_RECORDS
layout(rgba32ui) writeonly uniform uimage2DArray probe_hits;
layout(rgba32ui) writeonly uniform uimage2DArray probe_factors;

void store_probe_record(ivec3 p, int bounce, ProbeRecord r) {
    ivec3 q = ivec3(p.xy, probe_record_layer(p.z, bounce, imageSize(dst).z));
    imageStore(probe_hits, q, probe_record_hit(r));
    imageStore(probe_factors, q, probe_record_factors(r));
}
#endif

void main() {
    ivec3 p;
    if (!ray_pass_pixel(EFFECT_REFLECTIONS, imageSize(dst), p)) return;
    Rng rng = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT);
    rq_blend_begin(rng);   // alphaMode BLEND: this pixel's decisions
    PathVertex s = path_vertex_at_gbuffer(gbuf_load(p), uint(p.z));
    vec3 throughput = vec3(1.0);
    vec3 radiance = vec3(0.0);
    vec3 medium = vec3(0.0);
#if PROBE_RECORDS
    int recorded = 0;   // records stored; the rest are stored empty after the loop
#endif
    int reflections = 0;   // bounces that reflected (REFLECTION_BOUNCES at most; the rest transmit)
    for (int bounce = 0; bounce < MAX_BOUNCES; ++bounce) {
        BsdfSample bs;
        if (!bsdf_sample_specular(s.bsdf, s.n, s.v, rng_next3(rng), bs)) break;
        if (!bs.transmitted && ++reflections > REFLECTION_BOUNCES) break;   // the glossy fallback has it
        float side = dot(bs.l, s.ng);
        if (bs.transmitted ? side >= 0.0 : side <= 0.0) break;
        throughput *= bs.weight;
        if (!(max3(throughput) > 0.0)) break;
        if (bs.transmitted && !s.bsdf.thin) medium = s.bsdf.inside ? vec3(0.0) : s.attenuation;
        Hit hit;
        // Light this ray finds: all of it behind a delta or a transmission (light sampling finds
        // none), else its power-heuristic share with the light sample of the vertex it left
        // (shade_direct_mis there weighs the other share)
        bool whole = bs.delta || bs.transmitted;
        if (!trace_closest(offset_ray_origin(s.pos, bs.transmitted ? -s.ng : s.ng), bs.l, 1e30,
                           path_vertex_skip(s, bs.l), hit)) {
            float w = whole ? 1.0 : power_heuristic(bs.pdf, environment_light_pdf(bs.l));
            radiance += throughput * environment_radiance(bs.l) * w;
            break;
        }
        if (max3(medium) > 0.0) throughput *= exp(-medium * hit.t);
        float spread = cone_spread_after_bounce(s.cone_spread, bs.pdf, bs.delta);
        SurfacePoint sp;
        MaterialParams mp;
        vec3 from = s.pos;
        s = path_vertex_at_hit(hit, bs.l, s.cone_width + hit.t * spread, spread, sp, mp);
        vec3 emitted = vec3(0.0);
#if SCENE_HAS_EMISSIVE_TRIANGLES
        if (max3(mp.emissive) > 0.0 && (sp.front_face || mp.double_sided))
            emitted = mp.emissive * (whole ? 1.0 : power_heuristic(bs.pdf, emissive_light_pdf(sp, hit.instance, from)));
#endif
        // Only surfaces that are themselves reflective carry the path further; a reflected ray
        // leaves this vertex while reflections are left, a transmitted one while bounces are.
        bool continues = mp.effect >= EFFECT_REFLECTIONS;
        bool reflects_on = bounce + 1 < MAX_BOUNCES && reflections < REFLECTION_BOUNCES;
#if PROBE_RECORDS   // stored before the shadow rays: nothing of it stays live across their traversal
        store_probe_record(p, bounce, probe_record_at(s, throughput, continues && !reflects_on));
        recorded = bounce + 1;
#endif
        // (probe_gi_diffuse and probe_gi_glossy are 0 unless PROBE_GI: the in-kernel reference)
        radiance += throughput * (emitted + shade_direct_mis(s, rng, continues && reflects_on)
                                  + probe_gi_diffuse(s));
        if (!continues) break;
        if (!reflects_on) radiance += throughput * probe_gi_glossy(s);
    }
#if PROBE_RECORDS
    for (int b = recorded; b < MAX_BOUNCES; ++b) store_probe_record(p, b, probe_record_none());
#endif
    imageStore(dst, p, vec4(to_half_range(nonfinite_scrub(radiance)), 1.0));   // the target is rgba16f
    ray_count_commit(uint(p.z));
}
