// Emission + unshadowed direct light for every pixel of every view, the environment where the
// view sees no surface (RASTER materials use it as is; with RASTER_ONLY the pixels the ray passes
// light are skipped), + the probes' indirect diffuse light with PROBE_GI.
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "shading.glsl"
#include "probe_gi.glsl"
#include "nonfinite.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(rgba16f) writeonly uniform image2DArray dst;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    uint effect = gbuf_effect_at(p);
    if (effect == GBUF_NO_GEOMETRY) {   // the sky: the environment through this pixel
        vec3 o, d;
        view_primary_ray(uint(p.z), vec2(p.xy) + 0.5 + views[p.z].jitter.xy, o, d);
        imageStore(dst, p, vec4(to_half_range(nonfinite_scrub(environment_radiance(d))), 1.0));
        return;
    }
#if RASTER_ONLY
    if (effect >= EFFECT_SHADOWS) return;   // lit by the ray passes instead
#endif
    GSurface g = gbuf_load(p);
    Rng rng = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT);
    PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
    // REFLECTIONS and above: RTReflections traces the specular lobes and shares their light (MIS)
    vec3 c = g.emissive + shade_direct_mis(s, rng, g.effect >= EFFECT_REFLECTIONS) + probe_gi_diffuse(s);
    imageStore(dst, p, vec4(to_half_range(nonfinite_scrub(c)), 1.0));   // the target is rgba16f
}
