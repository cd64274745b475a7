// Per-view camera data for all views of a frame: one SSBO, filled by rayvr.xr.views.ViewSet.pack().
// All positions are in *render space*: world space minus the frame's origin (a float64 point on
// the CPU, usually the head position), so scenes far from the world origin stay precise.
#pragma once

#include "view_records.glsl"   // ViewData

layout(std430, binding = RAYVR_VIEWS_SSBO) readonly buffer ViewsBlock {
    uvec4 frame_info;     // x: view count, y: frame index, z: accumulated sample index, w: flags
    ViewData views[];
};

#define RAYVR_VIEWS_FLAG_REVERSED_Z 1u   // projections are reversed-Z with an infinite far plane

uint view_count() { return frame_info.x; }
uint view_global_index(uint v) { return floatBitsToUint(views[v].jitter.z); }
uint frame_index() { return frame_info.y; }
bool views_reversed_z() { return (frame_info.w & RAYVR_VIEWS_FLAG_REVERSED_Z) != 0u; }

// Eye-space direction through `uv` in [0,1]^2 of view v (uv.y = 0 at the bottom row).
// Built from the same tangents as the projection, so rays register with the raster exactly.
vec3 view_ray_dir_eye(uint v, vec2 uv) {
    vec4 t = views[v].fov_tan;
    return normalize(vec3(mix(t.x, t.y, uv.x), mix(t.z, t.w, uv.y), -1.0));
}

// Angle in radians between neighbouring pixels' rays at the centre of view v: the spread of its
// primary rays' cones (scene.glsl surface_at_cone).
float view_pixel_spread(uint v) { return (views[v].fov_tan.w - views[v].fov_tan.z) / views[v].clip.w; }

// Pixel q lies within an image of `size` pixels.
bool pixel_inside(ivec2 q, ivec2 size) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size)); }

// Render-space primary ray of view v through the point `pixel` in pixels (pixel (x, y)'s centre is
// (x + 0.5, y + 0.5); callers add their sub-pixel offset or jitter).
void view_primary_ray(uint v, vec2 pixel, out vec3 origin, out vec3 dir) {
    vec2 uv = pixel / views[v].clip.zw;
    origin = views[v].eye.xyz;
    dir = normalize(mat3(views[v].inv_view) * view_ray_dir_eye(v, uv));
}
