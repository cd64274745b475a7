// Ray-traced G-buffer: one primary ray per pixel of every view (ray_group.glsl: a warp spans views), through
// the pixel centre + the view's TAA jitter like GBufferRaster samples; the same encoding
// (gbuf_encode) and the same targets. Alpha-masked materials are cut in the ray query's any-hit step,
// alphaMode BLEND ones kept with probability alpha there, by the raster's decision (RNG_SALT_GBUFFER).
// Textures are read at the level of the pixel's ray cone, as the raster's derivatives choose it.
#define GBUF_WRITER 1
#include "views.glsl"
#include "scene.glsl"
#include "ray_query.glsl"
#include "gbuffer.glsl"
#include "ray_group.glsl"

layout(local_size_x = RAY_GROUP_SIZE) in;

GBufferTexel primary_surface(uint v, ivec2 pixel) {
    vec3 o, d;
    view_primary_ray(v, vec2(pixel) + 0.5 + views[v].jitter.xy, o, d);
    // the raster's clip planes: only eye depths in [near, far] (reversed-Z: no far plane)
    float depth_per_t = -(views[v].view * vec4(d, 0.0)).z;
    float t_near = views[v].clip.x / depth_per_t;
    float t_far = views_reversed_z() ? 1e30 : views[v].clip.y / depth_per_t;
    Hit hit;
    rq_blend_begin(rng_init(uvec2(pixel), view_global_index(v), frame_index(), RNG_SALT_GBUFFER));   // alphaMode BLEND
    if (!trace_closest(o + d * t_near, d, t_far - t_near, hit)) return gbuf_no_geometry();
    // surface_at_cone turns the shading normal to the (viewer-facing) face normal's side, as the raster path does
    SurfacePoint s = surface_at_cone(hit, d, (t_near + hit.t) * view_pixel_spread(v));
    return gbuf_encode(v, s.position, s.normal, s.geometric_normal, s.front_face,
                       material_params_at(s.material, s.uv, s.uv_lod), s.material, s.exit_instance);
}

void main() {
    ivec3 p = ray_group_pixel();
    if (uint(p.z) >= view_count() || any(greaterThanEqual(p.xy, ivec2(views[p.z].clip.zw)))) return;
    gbuf_store(p, primary_surface(uint(p.z), p.xy));   // images gbuf_out_<channel>
}
