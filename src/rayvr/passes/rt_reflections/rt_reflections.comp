// Mirror / glossy reflections for the pixels whose effect is REFLECTIONS or above (those on the
// reflection list, dispatched indirectly, or with PIXELS_2D the whole image in tiles): sample the
// specular lobe (GGX VNDF; exact mirror at roughness 0), trace, shade the hit with emission and
// shadowed direct light, continue up to MAX_BOUNCES. Output: reflected radiance weighted by the
// specular BSDF, so the composite adds it to the direct light. With PROBE_GI each hit adds the
// probes' indirect diffuse light, and a path stopped by MAX_BOUNCES on a reflective surface their
// glossy fallback.
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "shading.glsl"
#include "probe_gi.glsl"

#if PIXELS_2D   // every pixel of the image; those whose effect needs no such rays leave at once
layout(local_size_x = RAY_GROUP_SIZE) in;
#else           // the pixels on the list
layout(local_size_x = PIXEL_LIST_GROUP) in;
#endif
layout(rgba16f) writeonly uniform image2DArray dst;
uniform vec3 background;

void main() {
    ivec3 p;
    if (!ray_pass_pixel(EFFECT_REFLECTIONS, imageSize(dst), p)) return;
    Rng rng = rng_init(uvec2(p.xy), uint(p.z), frame_index(), RNG_SALT);
    PathVertex s = path_vertex_at_gbuffer(gbuf_load(p), uint(p.z));
    vec3 throughput = vec3(1.0);
    vec3 radiance = vec3(0.0);
    for (int bounce = 0; bounce < MAX_BOUNCES; ++bounce) {
        vec3 l;
        bool valid;
        // A rough lobe already gets emitters through light sampling (specular term of shade_direct);
        // only a mirror, whose direct specular is zero, sees them through the reflection ray.
        bool mirror = bsdf_is_mirror(s.bsdf);
        throughput *= bsdf_sample_specular(s.bsdf, s.n, s.v, rng_next2(rng), l, valid);
        if (!valid || dot(l, s.ng) <= 0.0 || max3(throughput) <= 0.0) break;
        Hit hit;
        if (!trace_closest(offset_ray_origin(s.pos, s.ng), l, 1e30, hit)) {
            radiance += throughput * background;
            break;
        }
        float spread = cone_spread_after_bounce(s.cone_spread, mirror ? 0.0 : bsdf_pdf_specular(s.bsdf, s.n, s.v, l), mirror);
        SurfacePoint sp;
        MaterialParams mp;
        s = path_vertex_at_hit(hit, l, s.cone_width + hit.t * spread, spread, sp, mp);
        radiance += throughput * ((mirror ? mp.emissive : vec3(0.0)) + shade_direct(s, rng) + probe_gi_diffuse(s));
        // Only surfaces that are themselves reflective carry the path further.
        if (mp.effect < EFFECT_REFLECTIONS) break;
        if (bounce == MAX_BOUNCES - 1) radiance += throughput * probe_gi_glossy(s);
    }
    imageStore(dst, p, vec4(finite_or_zero(radiance), 1.0));
}
