// The hybrid G-buffer as compute passes read it: texture arrays (one layer per view) on fixed
// sampler units, decoded into one GSurface. A reading pass gets the seven units as #defines
// GBUF_POS_UNIT etc. (rayvr/passes/_common.py GBUFFER_UNITS; the formats are in
// rayvr/passes/gbuffer.py) before including this file.
#pragma once
// hdr.glsl is included here, outside any #if, because include guards are textual
#include "hdr.glsl"

// effect texture (r32ui): low byte effect id (rayvr.Effect), upper 24 bits material index;
// GBUF_NO_GEOMETRY where no surface was drawn (sky).
const uint GBUF_NO_GEOMETRY = 0xFFu;

uint gbuf_effect_of(uint word) { return word & 0xFFu; }
uint gbuf_material_of(uint word) { return word >> 8u; }
uint gbuf_pack_effect(uint effect, uint material) { return (material << 8u) | (effect & 0xFFu); }

#ifdef GBUF_WRITER
// What the G-buffer writers store per pixel (GBufferRaster's fragment shader, GBufferRT's compute
// shader), in the targets' pin order; one encoding for both. Needs views.glsl and scene.glsl.
struct GBufferTexel {
    vec4 pos;           // posW: render-space position, w = linear eye depth
    vec4 normal;        // normW
    vec4 face_normal;   // faceNormalW
    vec4 base_color;    // baseColor (rgb, alpha)
    vec2 metal_rough;   // metalRough
    vec4 emissive;      // emissive
    uint effect;        // effect word (gbuf_pack_effect)
    vec2 motion;        // motion in pixels: this frame - last frame
};

// The texel of the surface at render-space `pos` seen from view v: normals already facing the
// viewer, material m (index `material`). Motion comes from the unjittered view_proj and
// prev_view_proj, so it carries no TAA jitter.
GBufferTexel gbuf_encode(uint v, vec3 pos, vec3 n, vec3 ng, MaterialParams m, uint material) {
    GBufferTexel t;
    t.pos = vec4(pos, -(views[v].view * vec4(pos, 1.0)).z);
    t.normal = vec4(n, 0.0);
    t.face_normal = vec4(ng, 0.0);
    t.base_color = vec4(m.base_color, m.alpha);
    t.metal_rough = vec2(m.metallic, m.roughness);
    t.emissive = vec4(to_half_range(m.emissive), 0.0);   // the emissive target is rgba16f
    t.effect = gbuf_pack_effect(m.effect, material);
    vec4 now_clip = views[v].view_proj * vec4(pos, 1.0);
    vec4 before_clip = views[v].prev_view_proj * vec4(pos, 1.0);
    vec2 size = views[v].clip.zw;
    vec2 now = (now_clip.xy / now_clip.w * 0.5 + 0.5) * size;
    vec2 before = (before_clip.xy / before_clip.w * 0.5 + 0.5) * size;
    t.motion = now - before;
    return t;
}

// Where nothing was hit: the raster path's clear values (rayvr/passes/gbuffer.py OUTPUTS).
GBufferTexel gbuf_no_geometry() {
    GBufferTexel t;
    t.pos = vec4(0.0);
    t.normal = vec4(0.0);
    t.face_normal = vec4(0.0);
    t.base_color = vec4(0.0);
    t.metal_rough = vec2(0.0);
    t.emissive = vec4(0.0);
    t.effect = GBUF_NO_GEOMETRY;
    t.motion = vec2(0.0);
    return t;
}
#endif

struct GSurface {
    vec3 pos;          // render space
    vec3 n;            // shading normal, facing the viewer
    vec3 ng;           // geometric normal, facing the viewer
    vec3 base_color;
    float alpha;
    float metallic;
    float roughness;
    vec3 emissive;
    uint effect;
    uint material;
};

#ifdef GBUF_POS_UNIT
layout(binding = GBUF_POS_UNIT) uniform sampler2DArray gbuf_pos;
layout(binding = GBUF_NORMAL_UNIT) uniform sampler2DArray gbuf_normal;
layout(binding = GBUF_FACE_NORMAL_UNIT) uniform sampler2DArray gbuf_face_normal;
layout(binding = GBUF_BASE_COLOR_UNIT) uniform sampler2DArray gbuf_base_color;
layout(binding = GBUF_METAL_ROUGH_UNIT) uniform sampler2DArray gbuf_metal_rough;
layout(binding = GBUF_EFFECT_UNIT) uniform usampler2DArray gbuf_effect;
layout(binding = GBUF_EMISSIVE_UNIT) uniform sampler2DArray gbuf_emissive;

GSurface gbuf_load(ivec3 p) {
    GSurface s;
    s.pos = texelFetch(gbuf_pos, p, 0).xyz;
    s.n = normalize(texelFetch(gbuf_normal, p, 0).xyz);
    s.ng = normalize(texelFetch(gbuf_face_normal, p, 0).xyz);
    vec4 bc = texelFetch(gbuf_base_color, p, 0);
    s.base_color = bc.rgb;
    s.alpha = bc.a;
    vec2 mr = texelFetch(gbuf_metal_rough, p, 0).xy;
    s.metallic = mr.x;
    s.roughness = mr.y;
    s.emissive = texelFetch(gbuf_emissive, p, 0).rgb;
    uint e = texelFetch(gbuf_effect, p, 0).x;
    s.effect = gbuf_effect_of(e);
    s.material = gbuf_material_of(e);
    return s;
}
#endif
