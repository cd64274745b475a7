// Stage 2 of a probe update (rayvr.passes.ProbeGI; records in probe_rays.glsl): each invocation
// shades its ray's hit from stage 1. A miss adds no light, only its distance (PROBE_MISS_DEPTH times
// the depth limit, so that the sky's share can be told from far hits). A back face of a
// one-sided opaque material counts as near (so that Chebyshev hides the probe behind it) and adds
// no light. A surface adds the light it reflects, and glass what it passes from behind, from the
// previous update's probes (so bounces add up over updates) and draws one light sample,
// unshadowed: stage 3 (probe_shadow.comp) traces the shadow ray this stage records. Emission is
// left out: the light sample draws every emitter at the hit.
#define PROBE_GI 1
#include "probe_rays.glsl"
#include "shading.glsl"
#include "nonfinite.glsl"

#if LIGHT_SAMPLES != 1
#error "probe rays draw one light sample (one shadow ray each in probe_shadow.comp)"
#endif

layout(local_size_x = PROBE_RAYS) in;

uniform uint probe_frame;
uniform uint probe_step;          // update within the frame (warm-up)
uniform int probe_history;        // 0: no previous update (its textures are undefined)

void main() {
    uint probe = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    uint ray = gl_LocalInvocationID.x;
    if (probe >= probe_info.z) return;
    uint i = probe * uint(PROBE_RAYS) + ray;
    vec4 rec_hit = probe_rays[i].hit;
    uvec4 ids = probe_rays[i].ids;
    vec3 dir = probe_ray_direction(ray);
    uint kind = floatBitsToUint(rec_hit.w);
    float limit = probe_volumes[probe_volume_of(probe)].lo.w;
    vec4 radiance = vec4(0.0, 0.0, 0.0, limit * PROBE_MISS_DEPTH);   // a miss: beyond every hit (the sky's share)
    vec3 direct = vec3(0.0);
    vec3 origin = vec3(0.0), to = vec3(0.0);
    float tmax = 0.0;
    uint skip = SCENE_NO_INSTANCE;
    // A miss adds no light: the environment is in the light table, and every point that reads the
    // probes samples it directly (the probes hold light that scattered at least once).
    if (kind != PROBE_RAY_MISS) {
        Hit hit;
        hit.t = rec_hit.x;
        hit.barycentrics = rec_hit.yz;
        hit.instance = ids.x;
        hit.primitive = ids.y;
        SurfacePoint sp;
        MaterialParams mp;
        PathVertex s = path_vertex_at_hit(hit, dir, hit.t * PROBE_RAY_SPREAD, PROBE_RAY_SPREAD, sp, mp);
        if (!sp.front_face && !mp.double_sided && mp.transmission == 0.0) {   // glass's far side passes light
            kind = PROBE_RAY_BACKFACE;
            radiance.a = min(PROBE_BACKFACE_DEPTH * hit.t, limit);
        } else {
            radiance.a = min(hit.t, limit);
            if (probe_history != 0) radiance.rgb = probe_gi_diffuse_transmitted(s);
#if SCENE_HAS_LIGHTS
            Rng rng = rng_init(uvec2(probe, ray), probe_step, probe_frame, RNG_SALT_PROBE_SHADE);
            LightSample ls;
            direct = nonfinite_scrub(light_sample_unshadowed(s, rng_next3(rng), false, ls));
            if (direct.x + direct.y + direct.z > 0.0) {
                origin = offset_ray_origin(s.pos, s.ng);
                shadow_ray(s.pos, origin, ls, to, tmax);
                skip = path_vertex_skip(s, to);
            }
#endif
        }
    }
    probe_rays[i].hit = vec4(origin, tmax);
    probe_rays[i].ids = uvec4(floatBitsToUint(to), kind);
    probe_rays[i].radiance = vec4(nonfinite_scrub(radiance.rgb), radiance.a);
    probe_rays[i].direct = vec4(direct, exit_instance_pack(skip));   // the shadow stage's skip
}
