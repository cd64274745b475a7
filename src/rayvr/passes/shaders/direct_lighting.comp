// Emission + unshadowed direct light for every pixel of every view (RASTER materials use it as is;
// with RASTER_ONLY the pixels the ray passes light are skipped).
#include "views.glsl"
#include "gbuffer.glsl"
#include "shading.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(rgba16f, binding = 0) writeonly uniform image2DArray dst;
uniform vec3 background;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    uint effect = gbuf_effect_of(texelFetch(gbuf_effect, p, 0).x);
    if (effect == GBUF_NO_GEOMETRY) {
        imageStore(dst, p, vec4(background, 1.0));
        return;
    }
#if RASTER_ONLY
    if (effect >= EFFECT_SHADOWS) return;   // lit by the ray passes instead
#endif
    GSurface s = gbuf_load(p);
    vec3 v = normalize(views[p.z].eye.xyz - s.pos);
    Rng rng = rng_init(uvec2(p.xy), uint(p.z), frame_index(), RNG_SALT);
    vec3 c = s.emissive + shade_direct(s.pos, s.n, s.ng, v, bsdf_params(s.base_color, s.metallic, s.roughness), rng);
    imageStore(dst, p, vec4(c, 1.0));
}
