// Non-finite samples a pass scrubs (NaN or Inf radiance set to 0), counted on the GPU: one
// atomic counter per pass, in the render graph's counter buffer (rayvr.rendergraph.nonfinite),
// which binds the pass's own 4 bytes at RAYVR_NONFINITE_COUNTER before the pass runs. The profile
// and the compile report show the totals. The counter is touched only where a value is not finite
// (the rare path): a finite image costs the test it always had. Outside a graph, bind a counter
// first (NonFiniteCounters.bind), or the rare path writes wherever binding RAYVR_NONFINITE_COUNTER is.
#pragma once
#include "color.glsl"

layout(binding = RAYVR_NONFINITE_COUNTER, offset = 0) uniform atomic_uint rayvr_nonfinite;

// Count one scrubbed sample (call it only where one was found).
void nonfinite_count() { atomicCounterIncrement(rayvr_nonfinite); }

// c, or 0 and counted when a channel is NaN or Inf (the whole sample: one bad channel means the
// path's weight is wrong).
vec3 nonfinite_scrub(vec3 c) {
    if (is_finite(c)) return c;
    nonfinite_count();
    return vec3(0.0);
}

vec4 nonfinite_scrub(vec4 c) {
    if (is_finite(c)) return c;
    nonfinite_count();
    return vec4(0.0);
}
