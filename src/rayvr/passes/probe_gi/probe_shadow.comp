// Stage 3 of a probe update (rayvr.passes.ProbeGI; records in probe_rays.glsl): each invocation
// traces the shadow ray stage 2 recorded for its probe ray, if any, and records its visibility
// (the expected one through BLEND surfaces, as RTShadows'). A kernel of its own: a traversal
// runs fastest with no shading beside it (probe_trace.comp).
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
    uint i = probe * uint(PROBE_RAYS) + ray;
    vec3 direct = probe_rays[i].direct.rgb;
    if (direct.x + direct.y + direct.z <= 0.0) return;
    vec4 origin = probe_rays[i].hit;   // xyz, w: tmax
    vec3 dir = uintBitsToFloat(probe_rays[i].ids.xyz);
    Rng rng = rng_init(uvec2(probe, ray), probe_step, probe_frame, RNG_SALT_PROBE_SHADOW);
    rq_blend_begin(rng);
    uint skip = exit_instance_unpack(probe_rays[i].direct.a);
    probe_rays[i].direct.a = trace_transmittance(origin.xyz, dir, origin.w, skip);
}
