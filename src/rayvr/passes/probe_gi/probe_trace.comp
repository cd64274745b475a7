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
    vec3 radiance;
    float dist = vol.lo.w;
    Rng rng = rng_init(uvec2(probe, ray), probe_step, probe_frame, RNG_SALT);
    rq_blend_begin(rng);   // alphaMode BLEND: this ray's decisions
    Hit hit;
    if (trace_closest(origin, dir, 1e29, hit)) {
        SurfacePoint sp;
        MaterialParams mp;
        PathVertex s = path_vertex_at_hit(hit, dir, hit.t * PROBE_RAY_SPREAD, PROBE_RAY_SPREAD, sp, mp);
        rec.ids = uvec4(hit.instance, hit.primitive, 0u, 0u);
        kind = PROBE_RAY_SURFACE;
        if (!sp.front_face && !mp.double_sided) {
            kind = PROBE_RAY_BACKFACE;
            radiance = vec3(0.0);
            dist = min(PROBE_BACKFACE_DEPTH * hit.t, dist);
        } else {
            radiance = shade_direct(s, rng);
            dist = min(hit.t, dist);
        }
    } else {
        radiance = environment_radiance(dir);
    }
    rec.radiance = vec4(nonfinite_scrub(radiance), dist);
    rec.hit = vec4(hit.t, hit.barycentrics, uintBitsToFloat(kind));
    probe_rays[probe * uint(PROBE_RAYS) + ray] = rec;
}
