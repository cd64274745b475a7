// The traced pixels a pixel the trace decision reconstructs takes its light from (rayvr/passes/
// trace_decision): a ray pass's fill (fill.comp) and SVGF's spread of filtered light across views
// (svgf_spread.comp) gather the same taps. DECISION_REUSE: bilinear over the traced pixels of its
// surface about its point's position in the source view; DECISION_FILL, or a REUSE none of whose
// four taps qualifies: the decision's one pixel (it traces and shows the surface). Needs
// views.glsl and gbuffer.glsl (GBUF_READER) first, and TRACE_DECISION 1.
#pragma once
#include "same_surface.glsl"
#include "trace_decision.glsl"

// A tap of the interpolation is the point's surface within this many pixel footprints.
const float DECISION_TAP_PIXELS = 1.5;

struct DecisionTaps {
    ivec3 q[4];
    vec4 w;   // weights summing to 1 (0: unused)
};

// The taps of pixel p (decision texel t, G-buffer surface g).
DecisionTaps decision_taps(ivec3 p, uvec2 t, GSurface g) {
    DecisionTaps taps;
    taps.w = vec4(0.0);
    if (decision_kind(t) == DECISION_REUSE) {
        ivec2 size = textureSize(trace_decision, 0).xy;
        vec2 b = decision_position(t) - 0.5;
        ivec2 base = ivec2(floor(b));
        vec2 f = b - vec2(base);
        for (int k = 0; k < 4; ++k) {
            ivec2 o = ivec2(k & 1, k >> 1);
            float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
            ivec3 q = ivec3(base + o, int(decision_view(t)));
            taps.q[k] = q;
            if (w > 0.0 && pixel_inside(q.xy, size) && decision_kind(decision_at(q)) == DECISION_TRACE
                && same_surface(g, uint(p.z), q, DECISION_TAP_PIXELS))
                taps.w[k] = w;
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
