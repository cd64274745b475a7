// Colour helpers shared by every shader: sRGB transfer functions, luminance, and the two ways
// radiance is made safe to store.
#pragma once

// Rec.709 / sRGB primaries, linear.
float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

float max3(vec3 c) { return max(c.x, max(c.y, c.z)); }

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

vec3 srgb_encode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

// True when every channel is a finite number.
bool is_finite(vec3 c) { return !(any(isnan(c)) || any(isinf(c))); }
bool is_finite(vec4 c) { return !(any(isnan(c)) || any(isinf(c))); }

// A radiance sample with a NaN or Inf channel becomes 0 (the whole sample: one bad channel means
// the path's weight is wrong). Radiance passes scrub with nonfinite.glsl, which also counts them.
vec3 finite_or_zero(vec3 c) { return is_finite(c) ? c : vec3(0.0); }
vec4 finite_or(vec4 c, vec4 fallback) { return is_finite(c) ? c : fallback; }

// Radiance kept in float16 targets (rgba16f): clamp to the largest half before storing, so a
// blinding emitter saturates at 65504 instead of becoming Inf (how a store converts a float above
// the half range is up to the driver), and negative or NaN values become 0.
const float HALF_MAX = 65504.0;

vec3 to_half_range(vec3 c) {
    return mix(clamp(c, vec3(0.0), vec3(HALF_MAX)), vec3(0.0), isnan(c));
}
