// The per-pixel trace decision (rayvr/passes/trace_decision): which pixels trace rays this frame
// and where each of the others takes its light from. TraceDecision writes one rg32ui texel per
// pixel and view before the ray passes:
//   x: the kind (bits 0-1) | DECISION_SPREAD (bit 2) | DECISION_SHARED_LIGHT (bit 3) | on a
//      DECISION_REUSE texel once its reader tested them (glsl/decision_taps.glsl; TraceDecision
//      writes 0), which of the four pixels about its source position show its surface traced
//      (bits 4-7, decision_tap_mask) | the ray budget at the pixel (bits 8-15, 0-255 for 0-1) |
//      the source's view (bits 16-23)
//   y: the source position in that view, in pixels (x | y << 16, each fixed point 13.3 bits)
// Kinds: DECISION_NONE no ray work (RASTER, or nothing drawn), DECISION_TRACE traced for real,
// DECISION_REUSE the shaded light of the same surface in another view, interpolated at the point's
// position there over the traced pixels of that surface, DECISION_FILL the light of one traced
// pixel of the same surface (the source pixel's centre), in its own view or another. Sources are
// traced pixels, so reconstruction is one dispatch after the tracing (passes/trace_decision/fill.comp).
// A pass that reads the decision defines TRACE_DECISION 1 and binds it to the sampler
// `trace_decision`; then decision_reconstructed(p) says a pixel leaves its rays to others and
// decision_density(p) is its budget (a denoiser widens its history and filter where it is low).
// DECISION_SPREAD marks a pixel whose light is another view's (REUSE, or FILL from another view)
// when the denoiser spreads the source's filtered light itself (TraceDecision `spread`, set with
// SVGF): the ray passes' fills and the composite leave it, SVGF writes it (svgf_spread.comp).
// DECISION_SHARED_LIGHT marks a traced pixel of effect SHADOWS or REFLECTIONS whose lobe cannot
// take another view's light, but whose direct light sample can (TraceDecision `share_light_samples`):
// RTShadows shades its own lobes over the sample its source pixel (decision_source) drew and the
// visibility that sample's shadow ray found, and traces no shadow ray for it; every other pass
// traces it as any other.
#pragma once
#ifndef TRACE_DECISION
#define TRACE_DECISION 0
#endif

const uint DECISION_NONE = 0u;
const uint DECISION_TRACE = 1u;
const uint DECISION_REUSE = 2u;
const uint DECISION_FILL = 3u;
const uint DECISION_SPREAD = 4u;   // a flag beside the kind
const uint DECISION_SHARED_LIGHT = 8u;   // another flag, on DECISION_TRACE

uint decision_kind(uvec2 t) { return t.x & 3u; }
bool decision_spread(uvec2 t) { return (t.x & DECISION_SPREAD) != 0u; }
bool decision_shared_light(uvec2 t) { return (t.x & DECISION_SHARED_LIGHT) != 0u; }
float decision_budget(uvec2 t) { return float((t.x >> 8u) & 0xFFu) / 255.0; }
const float DECISION_POSITION_STEPS = 8.0;   // sub-pixel steps of a source position
vec2 decision_position(uvec2 t) { return vec2(uvec2(t.y & 0xFFFFu, t.y >> 16u)) / DECISION_POSITION_STEPS; }
// A source position in the texel's fixed point steps (rounded, clamped to 16 bits).
uvec2 decision_position_steps(vec2 position) {
    return uvec2(clamp(position * DECISION_POSITION_STEPS + 0.5, vec2(0.0), vec2(65535.0)));
}
// A REUSE texel's light is interpolated over the pixels about its source position: tap k (0-3) is
// decision_tap_base(position) + (k & 1, k >> 1) of the source view, taken where bit k of
// decision_tap_mask is set (the pixel traces and shows the same surface, within
// DECISION_TAP_PIXELS footprints: glsl/decision_taps.glsl tests and reads it).
const uint DECISION_TAP_SHIFT = 4u;
const float DECISION_TAP_PIXELS = 1.5;
uint decision_tap_mask(uvec2 t) { return (t.x >> DECISION_TAP_SHIFT) & 15u; }
ivec2 decision_tap_base(vec2 position) { return ivec2(floor(position - 0.5)); }
uint decision_view(uvec2 t) { return (t.x >> 16u) & 0xFFu; }
ivec3 decision_source(uvec2 t) { return ivec3(ivec2(floor(decision_position(t))), int(decision_view(t))); }
// A texel for `kind` (with its flags and tap mask) at `budget` whose source is at `position` (pixels)
// of view `view`.
uvec2 decision_pack(uint kind, float budget, uint view, vec2 position) {
    uint b = uint(clamp(budget, 0.0, 1.0) * 255.0 + 0.5);
    uvec2 q = decision_position_steps(position);
    return uvec2(kind | (b << 8u) | (view << 16u), q.x | (q.y << 16u));
}

#if TRACE_DECISION
uniform usampler2DArray trace_decision;

uvec2 decision_at(ivec3 p) { return texelFetch(trace_decision, p, 0).xy; }
// The pixel takes its light from another pixel's rays this frame (it traces none).
bool decision_reconstructed(ivec3 p) { return decision_kind(decision_at(p)) >= DECISION_REUSE; }
float decision_density(ivec3 p) { return decision_budget(decision_at(p)); }
#endif
