// Radiance kept in float16 targets (rgba16f): clamp to the largest half before storing, so a
// blinding emitter saturates at 65504 instead of becoming Inf (how a store converts a float above
// the half range is up to the driver), and negative or NaN values become 0.
#pragma once

const float HALF_MAX = 65504.0;

vec3 to_half_range(vec3 c) {
    return mix(clamp(c, vec3(0.0), vec3(HALF_MAX)), vec3(0.0), isnan(c));
}
