// Emission + ray-traced shadowed direct light for the pixels on the shadow list (indirect dispatch).
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "shading.glsl"

layout(local_size_x = PIXEL_LIST_GROUP) in;
layout(rgba16f, binding = 0) writeonly uniform image2DArray dst;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pixel_count) return;
    ivec3 p = pixel_list_unpack(pixel_items[i]);
    GSurface s = gbuf_load(p);
    vec3 v = normalize(views[p.z].eye.xyz - s.pos);
    Rng rng = rng_init(uvec2(p.xy), uint(p.z), frame_index(), RNG_SALT);
    vec3 c = s.emissive + shade_direct(s.pos, s.n, s.ng, v, bsdf_params(s.base_color, s.metallic, s.roughness), rng);
    imageStore(dst, p, vec4(c, 1.0));
}
