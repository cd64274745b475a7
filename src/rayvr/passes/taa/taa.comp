// TAA: blend this frame's colour with the reprojected history (motion vectors, bilinear), the
// history first clamped to the 3x3 neighbourhood's colour box in YCoCg (mean +- sigma * std dev,
// grown to hold the pixel's own colour).
// On a still frame (rayvr/passes/history.py) a pixel that did not move keeps an exact running
// mean instead (weight 1 / frames, no clamp), so a still view converges to the mean of its jittered
// frames: the pixel-filtered image. The history's alpha holds the frames its mean stands for.
// All views in one dispatch; writes the output and the next frame's history.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
#include "color.glsl"
#include "nonfinite.glsl"
uniform sampler2DArray taa_color;
uniform sampler2DArray taa_history;   // linear, clamp to edge (sampler object)
#if TAA_HAS_MOTION
uniform sampler2DArray taa_motion;    // pixels, this frame - last frame
#endif
layout(TAA_DST_FORMAT) writeonly uniform image2DArray dst;
layout(rgba32f) writeonly uniform image2DArray history_out;
uniform float taa_alpha;          // weight of this frame
uniform float taa_sigma;          // colour box half-size in standard deviations
uniform bool taa_history_valid;
uniform bool taa_clamp;
uniform bool taa_still;           // this frame's views and scene are last frame's
uniform float taa_still_max;      // the frames a still pixel's mean may stand for

vec3 rgb_to_ycocg(vec3 c) {
    return vec3(0.25 * c.r + 0.5 * c.g + 0.25 * c.b, 0.5 * c.r - 0.5 * c.b, -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}

vec3 ycocg_to_rgb(vec3 c) {
    return vec3(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    vec4 current = nonfinite_scrub(texelFetch(taa_color, p, 0));   // counted once, here
    vec4 result = current;
    float frames = 1.0;   // what the new history stands for
    vec2 motion = vec2(0.0);
#if TAA_HAS_MOTION
    motion = texelFetch(taa_motion, p, 0).xy;
#endif
    vec2 prev = vec2(p.xy) + 0.5 - motion;
    if (taa_history_valid && taa_still && dot(motion, motion) < 1e-6) {
        vec4 history = texelFetch(taa_history, p, 0);
        frames = min(history.a + 1.0, taa_still_max);
        result.rgb = mix(history.rgb, current.rgb, 1.0 / frames);
    } else if (taa_history_valid && all(greaterThanEqual(prev, vec2(0.0))) && all(lessThanEqual(prev, vec2(size.xy)))) {
        vec4 history = texture(taa_history, vec3(prev / vec2(size.xy), float(p.z)));
        // a moving history stands for the frames of alpha's exponential window
        frames = min(history.a + 1.0, 1.0 / taa_alpha);
        if (taa_clamp) {
            vec3 m1 = vec3(0.0), m2 = vec3(0.0);
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    ivec3 q = ivec3(clamp(p.xy + ivec2(dx, dy), ivec2(0), size.xy - 1), p.z);
                    vec3 c = rgb_to_ycocg(finite_or_zero(texelFetch(taa_color, q, 0).rgb));   // counted at q
                    m1 += c;
                    m2 += c * c;
                }
            vec3 mean = m1 / 9.0;
            vec3 sd = sqrt(max(m2 / 9.0 - mean * mean, 0.0));
            // the box always holds this pixel's own colour, so a static image is a fixed point
            vec3 centre = rgb_to_ycocg(current.rgb);
            vec3 h = clamp(rgb_to_ycocg(history.rgb), min(mean - taa_sigma * sd, centre), max(mean + taa_sigma * sd, centre));
            history.rgb = ycocg_to_rgb(h);
        }
        result.rgb = mix(history.rgb, current.rgb, taa_alpha);
    }
    if (!is_finite(result)) {   // a non-finite history
        nonfinite_count();
        result = current;
        frames = 1.0;
    }
    imageStore(dst, p, result);
    imageStore(history_out, p, vec4(result.rgb, frames));
}
