// tools/variants (an experiment for tools/pt-variants `probe_trace_one_site`, not the tree's code):
// probe_trace.comp with the closest-hit ray and the hit's shadow ray traced by ONE rq_step call
// site in one loop, instead of trace_closest and shade_direct's trace_transmittance inlining two
// traversals (summing punctual lights in a second loop cost the H200's Reflections 2.4x: does the
// kernel's second traversal cost it too?). LIGHT_SAMPLES 1 only; the same rays, random numbers and
// results as the tree's kernel.
//
// Stage 1 of a probe update (rayvr.passes.ProbeGI): a workgroup per probe, an invocation per ray.
// Each traces one direction of a spherical Fibonacci set turned by this update's random rotation,
// shades the hit with shadowed direct light (emission is left out: shade_direct samples every
// emitter at the shading point already) and writes one ProbeRay record: the hit (for stage 2,
// probe_update.comp, to add the light the surface reflects from the previous update's probes) and
// its direct radiance and distance. Rays that leave the scene take the environment. The bounce
// lookup is a separate dispatch because, in the kernel that also traverses the BVH, its registers
// cost the traversal occupancy (on the H200 the one-kernel update took 1.17 ms for 16^3 x 128
// rays, of which the lookup was 0.6).
#define PROBE_GI 1
#include "probe_rays.glsl"
#include "shading.glsl"
#include "ray_query.glsl"
#include "nonfinite.glsl"

layout(local_size_x = PROBE_RAYS) in;

uniform uint probe_frame;
uniform uint probe_step;          // update within the frame (warm-up)

// One light sample at s, as shade_direct_mis draws it (specular not traced): its unshadowed
// f cos Le / pdf in `contribution` and the shadow ray that decides it; false where it adds nothing.
bool light_sample_unshadowed(PathVertex s, inout Rng rng, out vec3 contribution, out vec3 l, out float dist) {
    contribution = vec3(0.0);
    l = vec3(0.0, 0.0, 1.0);
    dist = 0.0;
#if SCENE_HAS_LIGHTS
    LightSample ls = sample_light(s.pos, rng_next3(rng));
    if (!ls.valid || dot(ls.direction, s.ng) <= 0.0) return false;
    vec3 f = bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
    if (f.x + f.y + f.z <= 0.0) return false;
    contribution = f * ls.weight;
    l = ls.direction;
    dist = ls.distance * (1.0 - 1e-4);
    return true;
#else
    return false;
#endif
}

void main() {
    uint probe = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    uint ray = gl_LocalInvocationID.x;
    if (probe >= probe_info.z) return;
    ProbeVolume vol = probe_volumes[probe_volume_of(probe)];
    vec3 origin = probe_position(vol, probe);
    vec3 dir = probe_ray_direction(ray);
    ProbeRay rec;
    rec.ids = uvec4(0u);
    uint kind = PROBE_RAY_MISS;
    vec3 radiance = vec3(0.0);
    float dist = vol.lo.w;
    Rng rng = rng_init(uvec2(probe, ray), probe_step, probe_frame, RNG_SALT);
    rq_blend_begin(rng);   // alphaMode BLEND: this ray's decisions
    Hit hit;
    hit.t = 1e29;
    hit.barycentrics = vec2(0.0);
    vec3 contribution = vec3(0.0);
    bool shadow = false;   // the loop's second ray
    rq_begin(origin, dir, 1e29, false);
    for (;;) {
        if (!rq_done && rq_step()) continue;   // the one traversal site
        if (!shadow) {
            if (!rq_found) {
                radiance = environment_radiance(dir);
                break;
            }
            hit = rq_hit;
            SurfacePoint sp;
            MaterialParams mp;
            PathVertex s = path_vertex_at_hit(hit, dir, hit.t * PROBE_RAY_SPREAD, PROBE_RAY_SPREAD, sp, mp);
            rec.ids = uvec4(hit.instance, hit.primitive, 0u, 0u);
            kind = PROBE_RAY_SURFACE;
            if (!sp.front_face && !mp.double_sided) {
                kind = PROBE_RAY_BACKFACE;
                dist = min(PROBE_BACKFACE_DEPTH * hit.t, dist);
                break;
            }
            dist = min(hit.t, dist);
            vec3 l;
            float d;
            if (!light_sample_unshadowed(s, rng, contribution, l, d)) break;
#if SCENE_HAS_ALPHA_BLEND   // trace_transmittance's expected visibility through BLEND surfaces
            rq_fractional = true;
            rq_transmittance = 1.0;
#endif
            rq_begin(offset_ray_origin(s.pos, s.ng), l, d, true);
            shadow = true;
            continue;
        }
        float visible = rq_found ? 0.0 : 1.0;
#if SCENE_HAS_ALPHA_BLEND
        rq_fractional = false;
        if (!rq_found) visible = rq_transmittance;
#endif
        radiance = contribution * visible;
        break;
    }
    rec.radiance = vec4(nonfinite_scrub(radiance), dist);
    rec.hit = vec4(hit.t, hit.barycentrics, uintBitsToFloat(kind));
    probe_rays[probe * uint(PROBE_RAYS) + ray] = rec;
}
