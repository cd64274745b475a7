// Whether a G-buffer pixel shows the same surface as another view's or pixel's (the trace
// decision's reuse and fill, rayvr/passes/trace_decision): the same effect word (effect and
// material), normals within ~25 degrees, and the point within a few pixel footprints of the other
// (divided by the cosine of the view angle: a grazing surface's pixels are long) and within one
// footprint of its plane. Needs views.glsl and gbuffer.glsl (GBUF_READER) first.
#pragma once

const float SAME_SURFACE_COS = 0.9;

// The size of a pixel of view v at render-space point x.
float pixel_footprint(uint v, vec3 x) { return distance(x, views[v].eye.xyz) * view_pixel_spread(v); }

// Pixel q (any view) shows surface g, seen from view v, within `pixels` footprints of g's point.
bool same_surface(GSurface g, uint v, ivec3 q, float pixels) {
    if (gbuf_fetch_effect(q) != gbuf_pack_effect(g.effect, g.material)) return false;
    vec3 x = gbuf_fetch_posW(q).xyz;
    if (dot(normalize(gbuf_fetch_faceNormalW(q).xyz), g.ng) < SAME_SURFACE_COS) return false;
    float size = max(pixel_footprint(v, g.pos), pixel_footprint(uint(q.z), x));
    vec3 d = x - g.pos;
    float cos_view = max(abs(dot(g.ng, normalize(views[v].eye.xyz - g.pos))), 0.2);
    return abs(dot(d, g.ng)) <= size && length(d) <= pixels * size / cos_view;
}
