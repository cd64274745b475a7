// ReSTIR DI stage 4, shading: emission + the final reservoir's sample, f cos Le G x W, with its own
// shadow ray (the expected transmittance through BLEND surfaces, as RTShadows), + the probes'
// indirect diffuse light with PROBE_GI: what RTShadows writes, from the resampled sample.
// With RESTIR_HINTS the ray's verdict sets (occluded) or clears (reached) the light's bit of the
// pixel's visibility hints, for next frame's targets (restir_di.glsl).
#include "restir_stage.glsl"
#include "ray_counters.glsl"
#include "probe_gi.glsl"
#include "nonfinite.glsl"

layout(rgba32ui) readonly uniform uimage2DArray reservoirs_in;
layout(rgba16f) writeonly uniform image2DArray dst;

void main() {
    ivec3 p;
    GSurface g;
    PathVertex s;
    if (!restir_pixel(imageSize(dst), p, g, s)) return;
    Reservoir r = reservoir_unpack(imageLoad(reservoirs_in, p));
    vec3 direct = vec3(0.0);
    if (r.weight > 0.0) {
        LightSample ls = light_id_eval(reservoir_light_id(r), s.pos);
        vec3 f = light_bsdf(s, ls, restir_specular_traced(g)) * ls.weight;
        if (max3(f) > 0.0) {
            vec3 origin = offset_ray_origin(s.pos, s.ng), dir;
            float tmax;
            shadow_ray(s.pos, origin, ls, dir, tmax);
            float visible = trace_transmittance(origin, dir, tmax, path_vertex_skip(s, dir));
            if (visible > 0.0) direct = f * (r.weight * visible);
#if RESTIR_HINTS
            uint hints = restir_hints_at(p), bit = restir_hint_bit(reservoir_light_id(r));
            uint updated = visible > 0.0 ? hints & ~bit : hints | bit;
            if (updated != hints) imageStore(restir_hints, p, uvec4(updated));
#endif
        }
    }
    ray_count_commit(uint(p.z));
    vec3 c = g.emissive + direct + probe_gi_diffuse(s);
    imageStore(dst, p, vec4(to_half_range(nonfinite_scrub(c)), 1.0));   // the target is rgba16f
}
