// Where a G-buffer pixel's surface was in last frame's view, and the disocclusion test that says
// whether last frame's pixel there showed this surface: the temporal passes' one rule (SVGF,
// ReSTIR DI). Needs GBUF_READER defined before it is included.
//
//   vec2 reprojected_pixel(ivec3 p)          last frame's pixel position of p's surface (the
//                                            G-buffer's motion; pixel (x, y)'s centre is x + 0.5)
//   float reprojected_depth(uint v, vec3 pos)    the linear depth pos had in view v last frame
//   vec2 gbuf_depth_gradient(ivec3 p, float z)   this frame's depth change per pixel at p
//   float reprojection_tolerance(float depth, vec2 gradient)
//   bool reprojection_matches(...)           the test itself
#pragma once
#include "views.glsl"
#include "gbuffer.glsl"

// Last frame's surface is this one when its normal is within ~25 degrees, its effect word
// (effect | material << 8) is the same and its depth is the depth this point had in last frame's
// view, within REPROJECT_DEPTH_TOLERANCE of it plus two pixels' depth gradient.
const float REPROJECT_NORMAL_COS = 0.9;
const float REPROJECT_DEPTH_TOLERANCE = 0.02;

vec2 reprojected_pixel(ivec3 p) { return vec2(p.xy) + 0.5 - gbuf_fetch_motion(p); }

float reprojected_depth(uint v, vec3 pos) { return (views[v].prev_view_proj * vec4(pos, 1.0)).w; }

// One axis of the depth gradient: the smaller of the one-sided differences towards neighbours
// that have geometry (depth > 0), so the gradient of a pixel on an edge is its own surface's.
float depth_slope(float z, float before, float after) {
    float a = before > 0.0 ? z - before : 1e30;
    float b = after > 0.0 ? after - z : 1e30;
    float s = abs(a) < abs(b) ? a : b;
    return s > 1e29 ? 0.0 : s;
}

// The depth gradient (per pixel) at a pixel of depth z from its neighbours' depths (0: no
// geometry, or outside the view) left, right, below and above.
vec2 depth_gradient(float z, float left, float right, float below, float above) {
    return vec2(depth_slope(z, left, right), depth_slope(z, below, above));
}

float gbuf_depth_or_none(ivec3 q, ivec2 size) { return pixel_inside(q.xy, size) ? gbuf_fetch_posW(q).w : 0.0; }

// The depth gradient at G-buffer pixel p of depth z in views of `size` pixels.
vec2 gbuf_depth_gradient(ivec3 p, float z, ivec2 size) {
    return depth_gradient(z, gbuf_depth_or_none(p + ivec3(-1, 0, 0), size), gbuf_depth_or_none(p + ivec3(1, 0, 0), size),
                          gbuf_depth_or_none(p + ivec3(0, -1, 0), size), gbuf_depth_or_none(p + ivec3(0, 1, 0), size));
}

// How far last frame's depth may lie from `depth` (reprojected_depth) at a pixel of this gradient.
float reprojection_tolerance(float depth, vec2 gradient) {
    return REPROJECT_DEPTH_TOLERANCE * depth + 2.0 * (abs(gradient.x) + abs(gradient.y));
}

// Whether last frame's surface (depth, normal n, effect word) is this frame's (the depth it had
// then, its normal and word), within `tolerance` of depth.
bool reprojection_matches(float depth, vec3 n, uint word, float then_depth, vec3 then_n, uint then_word, float tolerance) {
    return word == then_word && dot(n, then_n) >= REPROJECT_NORMAL_COS && abs(depth - then_depth) <= tolerance;
}
