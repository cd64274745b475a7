// Mirror / glossy reflections for the pixels whose effect is REFLECTIONS or above (those on the
// reflection list, dispatched indirectly, or with PIXELS_2D the whole image in tiles): sample the
// specular lobe (GGX VNDF; exact mirror at roughness 0), trace, shade the hit with emission and
// shadowed direct light, continue up to MAX_BOUNCES. Output: reflected radiance weighted by the
// specular BSDF, so the composite adds it to the direct light.
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "shading.glsl"

#if PIXELS_2D   // every pixel of the image; those whose effect needs no such rays leave at once
layout(local_size_x = RAY_GROUP_SIZE) in;
#else           // the pixels on the list
layout(local_size_x = PIXEL_LIST_GROUP) in;
#endif
layout(rgba16f, binding = 0) writeonly uniform image2DArray dst;
uniform vec3 background;

void main() {
    ivec3 p;
    if (!ray_pass_pixel(EFFECT_REFLECTIONS, imageSize(dst), p)) return;
    GSurface s = gbuf_load(p);
    Rng rng = rng_init(uvec2(p.xy), uint(p.z), frame_index(), RNG_SALT);

    vec3 pos = s.pos, n = s.n, ng = s.ng;
    vec3 v = normalize(views[p.z].eye.xyz - s.pos);
    BsdfParams m = bsdf_params(s.base_color, s.metallic, s.roughness);
    vec3 throughput = vec3(1.0);
    vec3 radiance = vec3(0.0);
    float cone_spread = view_pixel_spread(uint(p.z));   // the pixel's ray cone, for texture LOD
    float cone_width = distance(views[p.z].eye.xyz, s.pos) * cone_spread;
    for (int bounce = 0; bounce < MAX_BOUNCES; ++bounce) {
        vec3 l;
        bool valid;
        // A rough lobe already gets emitters through light sampling (specular term of shade_direct);
        // only a mirror, whose direct specular is zero, sees them through the reflection ray.
        bool mirror = bsdf_is_mirror(m);
        throughput *= bsdf_sample_specular(m, n, v, rng_next2(rng), l, valid);
        if (!valid || dot(l, ng) <= 0.0 || max(throughput.x, max(throughput.y, throughput.z)) <= 0.0) break;
        Hit hit;
        if (!trace_closest(offset_ray_origin(pos, ng), l, 1e30, hit)) {
            radiance += throughput * background;
            break;
        }
        cone_spread = cone_spread_after_bounce(cone_spread, mirror ? 0.0 : bsdf_pdf_specular(m, n, v, l), mirror);
        cone_width += hit.t * cone_spread;
        SurfacePoint sp = surface_at_cone(hit, l, cone_width);
        MaterialParams mp = material_params_at(sp.material, sp.uv, sp.uv_lod);
        BsdfParams hm = bsdf_params(mp.base_color, mp.metallic, mp.roughness);
        radiance += throughput * ((mirror ? mp.emissive : vec3(0.0)) + shade_direct(sp.position, sp.normal, sp.geometric_normal, -l, hm, rng));
        // Only surfaces that are themselves reflective carry the path further.
        if (mp.effect < EFFECT_REFLECTIONS) break;
        pos = sp.position; n = sp.normal; ng = sp.geometric_normal; v = -l; m = hm;
    }
    radiance = mix(radiance, vec3(0.0), bvec3(any(isnan(radiance)) || any(isinf(radiance))));
    imageStore(dst, p, vec4(radiance, 1.0));
}
