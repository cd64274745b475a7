// The traced pixels a pixel the trace decision reconstructs takes its light from (rayvr/passes/
// trace_decision): a ray pass's fill (fill.comp) and SVGF's spread of filtered light across views
// (svgf_spread.comp) gather the same taps. DECISION_REUSE: bilinear over the traced pixels of its
// surface about its point's position in the source view; DECISION_FILL, or a REUSE none of whose
// four taps qualifies: the decision's one pixel (it traces and shows the surface). Which taps
// qualify, the reader tests (decision_tested_taps: TraceDecision leaves the tap mask 0, as the
// test costs it more than its readers) and the texel then carries them (SVGF's `spreadSource` keeps
// it, for the reprojection's borrowed history: decision_taps). Needs views.glsl and gbuffer.glsl
// (GBUF_READER) first, and TRACE_DECISION 1.
#pragma once
#include "same_surface.glsl"
#include "trace_decision.glsl"

struct DecisionTaps {
    ivec3 q[4];
    vec4 w;   // weights summing to 1 (0: unused)
};

// Tap k (0-3) of a REUSE texel t: a pixel of its source view about its source position.
ivec3 decision_tap(uvec2 t, int k) {
    return ivec3(decision_tap_base(decision_position(t)) + ivec2(k & 1, k >> 1), int(decision_view(t)));
}

// Texel t of pixel p (surface g) with its tap mask: the taps that trace this frame and show g's
// surface within DECISION_TAP_PIXELS footprints.
uvec2 decision_tested_taps(ivec3 p, uvec2 t, GSurface g) {
    if (decision_kind(t) != DECISION_REUSE) return t;
    ivec2 size = textureSize(trace_decision, 0).xy;
    uint mask = 0u;
    for (int k = 0; k < 4; ++k) {
        ivec3 q = decision_tap(t, k);
        if (pixel_inside(q.xy, size) && decision_kind(decision_at(q)) == DECISION_TRACE
            && same_surface(g, uint(p.z), q, DECISION_TAP_PIXELS))
            mask |= 1u << uint(k);
    }
    return uvec2((t.x & ~(15u << DECISION_TAP_SHIFT)) | (mask << DECISION_TAP_SHIFT), t.y);
}

// The taps of a pixel whose decision texel t carries its tap mask (decision_tested_taps).
DecisionTaps decision_taps(uvec2 t) {
    DecisionTaps taps;
    taps.w = vec4(0.0);
    if (decision_kind(t) == DECISION_REUSE) {
        vec2 at = decision_position(t);
        vec2 f = at - 0.5 - vec2(decision_tap_base(at));
        uint mask = decision_tap_mask(t);
        for (int k = 0; k < 4; ++k) {
            float w = ((k & 1) == 1 ? f.x : 1.0 - f.x) * ((k >> 1) == 1 ? f.y : 1.0 - f.y);
            taps.q[k] = decision_tap(t, k);
            if (w > 0.0 && (mask & (1u << uint(k))) != 0u) taps.w[k] = w;
        }
    }
    float total = dot(taps.w, vec4(1.0));
    if (!(total > 1e-3)) {
        taps.q[0] = decision_source(t);
        taps.w = vec4(1.0, 0.0, 0.0, 0.0);
    } else {
        taps.w /= total;
    }
    return taps;
}
