// Stage 1 of a probe update (rayvr.passes.ProbeGI; records in probe_rays.glsl): each invocation
// traces one direction of a spherical Fibonacci set, turned by this update's random rotation, from
// its probe and records the closest hit. Nothing else happens here: the traversal kernel runs
// about 3x faster without the shading's registers beside it, so shading and the shadow ray are
// stages of their own (benchmarks/RESULTS.md, "where the probe update's time went").
#define PROBE_GI 1
#include "probe_rays.glsl"
#include "ray_query.glsl"

layout(local_size_x = PROBE_RAYS) in;

uniform uint probe_frame;
uniform uint probe_step;          // update within the frame (warm-up)

void main() {
    uint probe = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    uint ray = gl_LocalInvocationID.x;
    if (probe >= probe_info.z) return;
    vec3 origin = probe_position(probe_volumes[probe_volume_of(probe)], probe);
    Rng rng = rng_init(uvec2(probe, ray), probe_step, probe_frame, RNG_SALT_PROBE_TRACE);
    rq_blend_begin(rng);   // alphaMode BLEND: this ray's decisions
    Hit hit;
    bool found = trace_closest(origin, probe_ray_direction(ray), 1e29, hit);
    uint i = probe * uint(PROBE_RAYS) + ray;
    probe_rays[i].hit = vec4(hit.t, hit.barycentrics, uintBitsToFloat(found ? PROBE_RAY_SURFACE : PROBE_RAY_MISS));
    probe_rays[i].ids = uvec4(hit.instance, hit.primitive, 0u, 0u);
}
