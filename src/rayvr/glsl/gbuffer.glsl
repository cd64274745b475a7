// The hybrid G-buffer: one texture array per channel, one layer per view. The channels, their
// formats and the GLSL to read and write them are generated from rayvr/passes/gbuffer/channels.py
// ("gbuffer_channels.glsl"): GBufferTexel has one field per channel, named as its pin.
//   readers:  #define GBUF_READER 1, then gbuf_load(p) (or gbuf_fetch_<channel>(p)); the pass binds
//             its channel inputs to the samplers gbuf_<channel> (channels.bind_inputs).
//   writers:  #define GBUF_WRITER 1 (compute: gbuf_store(p, t) into images gbuf_out_<channel>;
//             raster: also GBUF_RASTER_WRITER, gbuf_output(t)); gbuf_encode() / gbuf_no_geometry()
//             are the one encoding of GBufferRaster and GBufferRT.
#pragma once
// included here, outside any #if, because include guards are textual
#include "color.glsl"
#include "gbuffer_channels.glsl"
#include "exit_instance.glsl"   // normW.w

// effect word (r32ui): low byte effect id (rayvr.Effect), upper 24 bits material index;
// GBUF_NO_GEOMETRY where no surface was drawn (sky).
const uint GBUF_NO_GEOMETRY = 0xFFu;

uint gbuf_effect_of(uint word) { return word & 0xFFu; }
uint gbuf_material_of(uint word) { return word >> 8u; }
uint gbuf_pack_effect(uint effect, uint material) { return (material << 8u) | (effect & 0xFFu); }

#ifdef GBUF_WRITER
// The effect a surface of material m is shaded with: its material's, but with REFLECTION_MAX_ROUGHNESS
// (rayvr/passes/gbuffer/reflection_cutoff.py) a REFLECTIONS surface rougher than that and not
// transmissive is shaded as SHADOWS (its specular light from the probes, not from one noisy ray).
uint gbuf_effect_for(MaterialParams m) {
#ifdef REFLECTION_MAX_ROUGHNESS
    if (m.effect == EFFECT_REFLECTIONS && m.roughness > REFLECTION_MAX_ROUGHNESS && !(m.transmission > 0.0))
        return EFFECT_SHADOWS;
#endif
    return m.effect;
}

// The texel of the surface at render-space `pos` seen from view v: normals already facing the
// viewer, `front_face` whether the viewer sees the side the winding makes the front, material m
// (index `material`), `exit_instance` what rays leaving on ng's side may skip (SurfacePoint's).
// The back of a single-sided emitter emits nothing (as a ray hit's in the path tracer);
// faceNormalW.w is 1 where the back is seen, so readers know a volume's inside.
// Motion comes from the unjittered view_proj and prev_view_proj, so it carries no TAA jitter.
// Needs views.glsl and scene.glsl.
GBufferTexel gbuf_encode(uint v, vec3 pos, vec3 n, vec3 ng, bool front_face, MaterialParams m, uint material,
                         uint exit_instance) {
    GBufferTexel t;
    t.posW = vec4(pos, -(views[v].view * vec4(pos, 1.0)).z);
    t.normW = vec4(n, exit_instance_pack(exit_instance));
    t.faceNormalW = vec4(ng, front_face ? 0.0 : 1.0);
    t.baseColor = vec4(m.base_color, m.alpha);
    // float16 rounds roughness either way: keep the side of the delta threshold (a near mirror
    // stays rough, as the path tracer's float32 material sees it; 1/512 > float16's half ulp)
    float r = m.roughness < MATERIAL_DELTA_ROUGHNESS ? 0.0 : max(m.roughness, MATERIAL_DELTA_ROUGHNESS * (1.0 + 1.0 / 512.0));
    t.metalRough = vec2(m.metallic, r);
    vec3 emitted = front_face || m.double_sided ? m.emissive : vec3(0.0);
    t.emissive = vec4(to_half_range(emitted), 0.0);   // the emissive target is rgba16f
    t.effect = gbuf_pack_effect(gbuf_effect_for(m), material);
    vec4 now_clip = views[v].view_proj * vec4(pos, 1.0);
    vec4 before_clip = views[v].prev_view_proj * vec4(pos, 1.0);
    vec2 size = views[v].clip.zw;
    vec2 now = (now_clip.xy / now_clip.w * 0.5 + 0.5) * size;
    vec2 before = (before_clip.xy / before_clip.w * 0.5 + 0.5) * size;
    t.motion = now - before;
    return t;
}

// Where nothing was hit: the channels' clear values (rayvr/passes/gbuffer/channels.py).
GBufferTexel gbuf_no_geometry() {
    GBufferTexel t;
    t.posW = vec4(0.0);
    t.normW = vec4(0.0);
    t.faceNormalW = vec4(0.0);
    t.baseColor = vec4(0.0);
    t.metalRough = vec2(0.0);
    t.emissive = vec4(0.0);
    t.effect = GBUF_NO_GEOMETRY;
    t.motion = vec2(0.0);
    return t;
}
#endif

// A G-buffer texel decoded for shading.
struct GSurface {
    vec3 pos;          // render space
    vec3 n;            // shading normal, facing the viewer
    vec3 ng;           // geometric normal, facing the viewer
    bool front_face;   // the viewer sees the side the winding makes the front
    vec3 base_color;
    float alpha;
    float metallic;
    float roughness;
    vec3 emissive;
    uint effect;
    uint material;
    uint exit_instance;   // SurfacePoint.exit_instance (0xFFFFFFFF: none)
};

#ifdef GBUF_READER
uint gbuf_effect_at(ivec3 p) { return gbuf_effect_of(gbuf_fetch_effect(p)); }

GSurface gbuf_load(ivec3 p) {
    GSurface s;
    s.pos = gbuf_fetch_posW(p).xyz;
    vec4 n = gbuf_fetch_normW(p);
    s.n = normalize(n.xyz);
    s.exit_instance = exit_instance_unpack(n.w);
    vec4 ng = gbuf_fetch_faceNormalW(p);
    s.ng = normalize(ng.xyz);
    s.front_face = ng.w < 0.5;
    vec4 bc = gbuf_fetch_baseColor(p);
    s.base_color = bc.rgb;
    s.alpha = bc.a;
    vec2 mr = gbuf_fetch_metalRough(p);
    s.metallic = mr.x;
    s.roughness = mr.y;
    s.emissive = gbuf_fetch_emissive(p).rgb;
    uint e = gbuf_fetch_effect(p);
    s.effect = gbuf_effect_of(e);
    s.material = gbuf_material_of(e);
    return s;
}
#endif
