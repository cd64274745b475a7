// SVGF stage 3, one iteration of the edge-avoiding a-trous wavelet filter (section 4.3): a 5x5
// B3-spline kernel with taps `svgf_step` pixels apart, each weighted by depth (against the depth
// gradient), normal and luminance (against the 3x3 Gaussian of the variance); the variance is
// filtered with the squared weights. With `svgf_write_history` the result is next frame's history.
#define SVGF_READS_SURFACE 1
#include "svgf_common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

uniform SVGF_ILLUM_SAMPLER src_illum;
layout(SVGF_ILLUM_FORMAT) writeonly uniform SVGF_ILLUM_IMAGE dst_illum;
layout(rgba16f) writeonly uniform image2DArray history_diffuse;
#if SVGF_SPECULAR
layout(rgba16f) writeonly uniform image2DArray history_specular;
#endif
uniform int svgf_step;
uniform bool svgf_write_history;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

// The variance at p blurred by a 3x3 Gaussian (x diffuse, y specular): a steadier luminance scale.
vec2 blurred_variance(ivec3 p, ivec2 size) {
    vec2 sum = vec2(0.0);
    float total = 0.0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            ivec3 q = p + ivec3(dx, dy, 0);
            if (!svgf_inside(q.xy, size)) continue;
            float k = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
            sum += k * svgf_illum_variance(texelFetch(src_illum, q, 0));
            total += k;
        }
    return sum / total;
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(dst_illum);
    if (any(greaterThanEqual(p, size))) return;
    float depth;
    vec3 n;
    bool geometry = svgf_key_at(p, size.xy, depth, n);
    SvgfIllum centre = texelFetch(src_illum, p, 0);
    if (!geometry) {   // nothing to filter: the texel as it came
        imageStore(dst_illum, p, centre);
        if (svgf_write_history) {
            imageStore(history_diffuse, p, vec4(svgf_illum_diffuse(centre).rgb, 0.0));
#if SVGF_SPECULAR
            imageStore(history_specular, p, vec4(svgf_illum_specular(centre).rgb, 0.0));
#endif
        }
        return;
    }
    vec4 d = svgf_illum_diffuse(centre), s = svgf_illum_specular(centre);
    {
        vec2 phi = svgf_phi_color * sqrt(max(blurred_variance(p, size.xy), 0.0) + 1e-10);
        vec2 gradient = svgf_depth_gradient(p, depth, size.xy);
        // Every weight is one exp2 of a sum of exponents (depth, normal, luminance: the same
        // product as svgf_weight_depth * svgf_weight_normal * exp(-|dl| / phi)), which spends
        // half the special-function work of evaluating the factors one by one.
        const float LOG2E = 1.4426950408889634;
        vec2 lum_scale = LOG2E / phi;
        float depth_eps = 1e-3 * depth + 1e-8;
        float grad_step = svgf_phi_depth * float(svgf_step);
        float ld = luminance(d.rgb), ls = luminance(s.rgb);
        float k0 = KERNEL[0] * KERNEL[0];
        vec2 sum_w = vec2(k0);
        vec3 sum_d = k0 * d.rgb, sum_s = k0 * s.rgb;
        vec2 sum_v = k0 * k0 * vec2(d.a, s.a);
        for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
                if (dx == 0 && dy == 0) continue;
                ivec3 q = p + ivec3(dx * svgf_step, dy * svgf_step, 0);
                float tap_depth;
                vec3 tap_n;
                if (!svgf_key_at(q, size.xy, tap_depth, tap_n)) continue;
                float e = -LOG2E * abs(depth - tap_depth) / (grad_step * abs(gradient.x * float(dx) + gradient.y * float(dy))
                                                             + depth_eps);
                if (svgf_phi_normal > 0.0) {
                    float c = dot(n, tap_n);
                    if (!(c > 0.0)) continue;   // weight 0
                    e += svgf_phi_normal * log2(c);
                }
                e += log2(KERNEL[abs(dx)] * KERNEL[abs(dy)]);
                SvgfIllum tap = texelFetch(src_illum, q, 0);
                vec4 qd = svgf_illum_diffuse(tap);
                float wd = exp2(e - abs(ld - luminance(qd.rgb)) * lum_scale.x);
                sum_w.x += wd;
                sum_d += wd * qd.rgb;
                sum_v.x += wd * wd * qd.a;
#if SVGF_SPECULAR
                vec4 qs = svgf_illum_specular(tap);
                float ws = exp2(e - abs(ls - luminance(qs.rgb)) * lum_scale.y);
                sum_w.y += ws;
                sum_s += ws * qs.rgb;
                sum_v.y += ws * ws * qs.a;
#endif
            }
        d = vec4(sum_d / sum_w.x, sum_v.x / (sum_w.x * sum_w.x));
        s = vec4(sum_s / sum_w.y, sum_v.y / (sum_w.y * sum_w.y));
    }
    imageStore(dst_illum, p, svgf_illum_pack(d, s));
    if (svgf_write_history) imageStore(history_diffuse, p, vec4(d.rgb, 0.0));
#if SVGF_SPECULAR
    if (svgf_write_history) imageStore(history_specular, p, vec4(s.rgb, 0.0));
#endif
}
