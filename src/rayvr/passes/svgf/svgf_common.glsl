// SVGF's shared pieces (rayvr/passes/svgf): the surface each stage keeps per pixel (packed in
// rgba32ui: linear depth, octahedral normal, effect word, history length), demodulation by the
// BSDF's directional albedos, and the edge-stopping weights of the variance estimate and the
// a-trous filter (Schied et al. 2017, section 4).
#pragma once
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "path_vertex.glsl"
#include "nonfinite.glsl"

// Demodulation divides by max(albedo, SVGF_ALBEDO_EPS) and remodulation multiplies by the same,
// so a black lobe round-trips exactly.
const float SVGF_ALBEDO_EPS = 1e-3;
// Disocclusion: last frame's surface at the reprojected pixel is this one when its normal is
// within ~25 degrees, its effect word (effect | material << 8) is the same and its depth is the
// depth this point had in last frame's view, within SVGF_DEPTH_TOLERANCE of it plus two pixels'
// depth gradient.
const float SVGF_NORMAL_COS = 0.9;
const float SVGF_DEPTH_TOLERANCE = 0.02;
// Below this history length the variance comes from a 7x7 neighbourhood (section 4.2).
const float SVGF_MIN_HISTORY = 4.0;

uniform float svgf_phi_depth;    // sigma_z
uniform float svgf_phi_normal;   // sigma_n
uniform float svgf_phi_color;    // sigma_l

struct SvgfSurface {
    float depth;      // linear eye depth; 0: no geometry
    vec3 n;           // shading normal (render space)
    uint word;        // G-buffer effect word
    float history;    // frames in this pixel's history (0: none)
};

vec2 svgf_sign(vec2 v) { return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

uint svgf_pack_normal(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z) + 1e-20;
    vec2 e = n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * svgf_sign(n.xy);
    return packSnorm2x16(e);
}

vec3 svgf_unpack_normal(uint bits) {
    vec2 e = unpackSnorm2x16(bits);
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * svgf_sign(n.xy);
    return normalize(n);
}

uvec4 svgf_pack(SvgfSurface s) {
    return uvec4(floatBitsToUint(s.depth), svgf_pack_normal(s.n), s.word, floatBitsToUint(s.history));
}

SvgfSurface svgf_unpack(uvec4 u) {
    SvgfSurface s;
    s.depth = uintBitsToFloat(u.x);
    s.n = svgf_unpack_normal(u.y);
    s.word = u.z;
    s.history = uintBitsToFloat(u.w);
    return s;
}

bool svgf_has_geometry(uint word) { return gbuf_effect_of(word) != GBUF_NO_GEOMETRY; }

SvgfSurface svgf_no_geometry() {
    SvgfSurface s;
    s.depth = 0.0;
    s.n = vec3(0.0, 0.0, 1.0);
    s.word = GBUF_NO_GEOMETRY;
    s.history = 0.0;
    return s;
}

bool svgf_inside(ivec2 q, ivec2 size) { return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size)); }

// The directional albedos of the diffuse and specular lobes at G-buffer surface g seen from `view`.
void svgf_albedo(GSurface g, uint view, out vec3 diffuse, out vec3 specular) {
    PathVertex s = path_vertex_at_gbuffer(g, view);
    bsdf_albedo(s.bsdf, s.n, s.v, diffuse, specular);
}

vec3 svgf_demodulate(vec3 radiance, vec3 albedo) {
    return to_half_range(max(nonfinite_scrub(radiance), 0.0) / max(albedo, vec3(SVGF_ALBEDO_EPS)));
}

vec3 svgf_remodulate(vec3 illumination, vec3 albedo) { return illumination * max(albedo, vec3(SVGF_ALBEDO_EPS)); }

// One axis of the depth gradient: the smaller of the one-sided differences towards neighbours
// that have geometry (depth > 0), so the gradient of a pixel on an edge is its own surface's.
float svgf_depth_slope(float z, float before, float after) {
    float a = before > 0.0 ? z - before : 1e30;
    float b = after > 0.0 ? after - z : 1e30;
    float s = abs(a) < abs(b) ? a : b;
    return s > 1e29 ? 0.0 : s;
}

// w_z: depth difference against the depth gradient's prediction over `offset` pixels.
float svgf_weight_depth(float zp, float zq, vec2 gradient, vec2 offset) {
    return exp(-abs(zp - zq) / (svgf_phi_depth * abs(dot(gradient, offset)) + 1e-3 * zp + 1e-8));
}

// w_n: normals that agree (phi 0: any normal).
float svgf_weight_normal(vec3 np, vec3 nq) {
    return svgf_phi_normal > 0.0 ? pow(max(dot(np, nq), 0.0), svgf_phi_normal) : 1.0;
}

#ifdef SVGF_READS_SURFACE
// This frame's surfaces (the reprojection stage's output), for the stages after it.
uniform usampler2DArray surface_cur;

float svgf_depth_at(ivec3 q, ivec2 size) {
    return svgf_inside(q.xy, size) ? uintBitsToFloat(texelFetch(surface_cur, q, 0).x) : 0.0;
}

// The depth gradient (per pixel) at p, whose depth is z.
vec2 svgf_depth_gradient(ivec3 p, float z, ivec2 size) {
    return vec2(svgf_depth_slope(z, svgf_depth_at(p + ivec3(-1, 0, 0), size), svgf_depth_at(p + ivec3(1, 0, 0), size)),
                svgf_depth_slope(z, svgf_depth_at(p + ivec3(0, -1, 0), size), svgf_depth_at(p + ivec3(0, 1, 0), size)));
}
#endif
