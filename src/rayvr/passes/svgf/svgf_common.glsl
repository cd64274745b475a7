// SVGF's shared pieces (rayvr/passes/svgf): the surface each stage keeps per pixel (packed in
// two rg32ui textures: the filter key, linear depth and octahedral normal, which the variance and
// a-trous stages compare per tap; and the effect word and history length, which only the
// reprojection compares per tap), the illumination
// texel between the stages (both lobes and their variances in one texel), demodulation by the
// BSDF's directional albedos, and the edge-stopping weights of the variance estimate and the
// a-trous filter (Schied et al. 2017, section 4).
#pragma once
#ifndef SVGF_SHARED
#define SVGF_SHARED 0   // 1: views borrow other views' filtered light (svgf_spread.comp); needs TRACE_DECISION
#endif
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "demodulation.glsl"
#include "nonfinite.glsl"
#include "octahedral.glsl"
#include "reprojection.glsl"   // the disocclusion test and depth gradients

// Below this history length the variance comes from a 7x7 neighbourhood (section 4.2).
const float SVGF_MIN_HISTORY = 4.0;

uniform float svgf_phi_depth;    // sigma_z
uniform float svgf_phi_normal;   // sigma_n
uniform float svgf_phi_color;    // sigma_l

struct SvgfSurface {
    float depth;      // linear eye depth; 0: no geometry
    vec3 n;           // shading normal (render space)
    uint word;        // G-buffer effect word
    float history;    // frames in this pixel's history (0: none; SVGF_BORROWED: its sources')
};

// The history length of a pixel whose light, and history, this frame were other pixels' (another
// view's, svgf_spread.comp): the pixels its decision texel (`spread_source`) names hold them.
const float SVGF_BORROWED = -1.0;

// The filter key: linear depth (float bits; 0: no geometry, a drawn point's depth being
// positive) and the octahedral normal (snorm16x2), 64 bits a tap.
uvec2 svgf_pack_key(SvgfSurface s) { return uvec2(floatBitsToUint(s.depth), oct_pack_snorm16(s.n)); }
// The rest: effect word and history length (float bits).
uvec2 svgf_pack_tag(SvgfSurface s) { return uvec2(s.word, floatBitsToUint(s.history)); }

SvgfSurface svgf_unpack(uvec2 key, uvec2 tag) {
    SvgfSurface s;
    s.depth = uintBitsToFloat(key.x);
    s.n = oct_unpack_snorm16(key.y);
    s.word = tag.x;
    s.history = uintBitsToFloat(tag.y);
    return s;
}

float svgf_key_depth(uvec2 key) { return uintBitsToFloat(key.x); }

// The illumination between the stages, both lobes in one texel so that a tap is one fetch: with
// SVGF_SPECULAR rgba32ui of float16 pairs (diffuse rg), (diffuse b, its variance), (specular rg),
// (specular b, its variance); without, rgba16f (diffuse rgb, its variance). Stages declare
// `uniform SVGF_ILLUM_SAMPLER name;` and `layout(SVGF_ILLUM_FORMAT) uniform SVGF_ILLUM_IMAGE name;`.
#if SVGF_SPECULAR
#define SVGF_ILLUM_FORMAT rgba32ui
#define SVGF_ILLUM_SAMPLER usampler2DArray
#define SVGF_ILLUM_IMAGE uimage2DArray
#define SvgfIllum uvec4
SvgfIllum svgf_illum_pack(vec4 d, vec4 s) {
    return uvec4(packHalf2x16(d.rg), packHalf2x16(d.ba), packHalf2x16(s.rg), packHalf2x16(s.ba));
}
vec4 svgf_illum_diffuse(SvgfIllum t) { return vec4(unpackHalf2x16(t.x), unpackHalf2x16(t.y)); }
vec4 svgf_illum_specular(SvgfIllum t) { return vec4(unpackHalf2x16(t.z), unpackHalf2x16(t.w)); }
vec2 svgf_illum_variance(SvgfIllum t) { return vec2(unpackHalf2x16(t.y).y, unpackHalf2x16(t.w).y); }
#else
#define SVGF_ILLUM_FORMAT rgba16f
#define SVGF_ILLUM_SAMPLER sampler2DArray
#define SVGF_ILLUM_IMAGE image2DArray
#define SvgfIllum vec4
SvgfIllum svgf_illum_pack(vec4 d, vec4 s) { return d; }
vec4 svgf_illum_diffuse(SvgfIllum t) { return t; }
vec4 svgf_illum_specular(SvgfIllum t) { return vec4(0.0); }
vec2 svgf_illum_variance(SvgfIllum t) { return vec2(t.a, 0.0); }
#endif

// The surface of pixel p with geometry (G-buffer surface g, effect word `word`), `history` frames old.
SvgfSurface svgf_surface_at(ivec3 p, GSurface g, uint word, float history) {
    return SvgfSurface(max(gbuf_fetch_posW(p).w, 1e-30), g.n, word, history);   // depth > 0: the key says geometry
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

bool svgf_inside(ivec2 q, ivec2 size) { return pixel_inside(q, size); }

// A lobe's radiance demodulated (demodulation.glsl), non-finite samples scrubbed, in float16 range.
vec3 svgf_demodulate(vec3 radiance, vec3 albedo) { return to_half_range(demodulate(nonfinite_scrub(radiance), albedo)); }

// The albedos SVGF takes each lobe's light apart from (demodulation.glsl) at G-buffer surface g
// seen from `view`: the specular lobe's own; for the diffuse lobe its own where it holds diffuse
// light alone (PATH_TRACED pixels, whose path tracer splits its lobes), else both lobes' together:
// the lighting passes return direct light with its highlights in the diffuse lobe (HybridComposite),
// at REFLECTIONS pixels too, where a punctual light's highlight stays whole (no reflection ray
// finds it), as does all light without a specular input. A metal's diffuse albedo is 0: a
// highlight divided by it alone became an illumination 1000x too bright, which the filter spread
// onto its neighbours' albedos.
void svgf_albedos(GSurface g, uint view, out vec3 diffuse, out vec3 specular) {
    surface_albedos(g, view, diffuse, specular);
    if (SVGF_SPECULAR == 0 || g.effect != EFFECT_PATH_TRACED) diffuse += specular;
}

// The output colour of G-buffer surface g seen from `view` (a pixel with geometry) from its
// filtered illumination: each lobe times its albedo, plus the surface's emission.
vec3 svgf_color(GSurface g, uint view, vec3 diffuse, vec3 specular) {
    vec3 albedo_d, albedo_s;
    svgf_albedos(g, view, albedo_d, albedo_s);
    vec3 c = remodulate(diffuse, albedo_d) + g.emissive;
#if SVGF_SPECULAR
    c += remodulate(specular, albedo_s);
#endif
    return c;
}
// The same for pixel p.
vec3 svgf_color(ivec3 p, vec3 diffuse, vec3 specular) { return svgf_color(gbuf_load(p), uint(p.z), diffuse, specular); }

// The output where nothing was drawn: the input `diffuse` (the background) as it came.
vec4 svgf_background(sampler2DArray diffuse, ivec3 p) { return vec4(to_half_range(texelFetch(diffuse, p, 0).rgb), 1.0); }

// The depth gradient as the a-trous iterations read it (the variance stage writes it once a
// frame, rg16f): finite, so that a zero offset times it stays zero.
vec2 svgf_gradient_store(vec2 gradient) { return clamp(gradient, vec2(-65504.0), vec2(65504.0)); }

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
uniform usampler2DArray key_cur;
uniform usampler2DArray surface_cur;

// Geometry at q (depth > 0) and its key; taps outside the view have none.
bool svgf_key_at(ivec3 q, ivec2 size, out float depth, out vec3 n) {
    uvec2 key = svgf_inside(q.xy, size) ? texelFetch(key_cur, q, 0).xy : uvec2(0u);
    depth = svgf_key_depth(key);
    n = depth > 0.0 ? oct_unpack_snorm16(key.y) : vec3(0.0, 0.0, 1.0);
    return depth > 0.0;
}

float svgf_depth_at(ivec3 q, ivec2 size) {
    return svgf_inside(q.xy, size) ? svgf_key_depth(texelFetch(key_cur, q, 0).xy) : 0.0;
}

// The depth gradient (per pixel) at p, whose depth is z, from the key.
vec2 svgf_depth_gradient(ivec3 p, float z, ivec2 size) {
    return depth_gradient(z, svgf_depth_at(p + ivec3(-1, 0, 0), size), svgf_depth_at(p + ivec3(1, 0, 0), size),
                          svgf_depth_at(p + ivec3(0, -1, 0), size), svgf_depth_at(p + ivec3(0, 1, 0), size));
}
#endif
