// SVGF stage 3, one iteration of the edge-avoiding a-trous wavelet filter (section 4.3): with
// SVGF_KERNEL 5 the paper's 5x5 B3-spline kernel (3/8, 1/4, 1/16 per axis, 25 taps), with
// SVGF_KERNEL 3 a 3x3 kernel (1/2, 1/4 per axis, 9 taps: A-SVGF's, Schied et al. 2018), taps
// `svgf_step` pixels apart, each weighted by depth (against the depth gradient the variance stage
// wrote), normal and luminance (against the 3x3 Gaussian of the variance); the variance is
// filtered with the squared weights. With `svgf_write_history` the result is next frame's history.
// Taps come in mirrored pairs (offsets o and -o), which share the depth weight's denominator.
// With SVGF_FINAL (the last iteration) the filtered illumination is not stored: it is remodulated
// into the output colour `dst` here (svgf_color; the background as it came where nothing was
// drawn), which spares a pass that would read it back (the modulate stage serves 0 iterations);
// with SVGF_SHARED it is stored too (`dst_illum`), for svgf_spread.comp to give other views.
#define SVGF_READS_SURFACE 1
#include "svgf_common.glsl"

#ifndef SVGF_FINAL
#define SVGF_FINAL 0
#endif
#if SVGF_SHARED && SVGF_FINAL   // the pixels svgf_spread.comp writes
#define TRACE_DECISION 1
#endif
#include "trace_decision.glsl"
#include "svgf_pixels.glsl"
uniform SVGF_ILLUM_SAMPLER src_illum;
#if SVGF_FINAL
uniform sampler2DArray svgf_diffuse_in;
layout(rgba16f) writeonly uniform image2DArray dst;
#define OUT_SIZE imageSize(dst)
#else
#define OUT_SIZE imageSize(dst_illum)
#endif
#if !SVGF_FINAL || SVGF_SHARED
layout(SVGF_ILLUM_FORMAT) writeonly uniform SVGF_ILLUM_IMAGE dst_illum;
#endif
layout(rgba16f) writeonly uniform image2DArray history_diffuse;
#if SVGF_SPECULAR
layout(rgba16f) writeonly uniform image2DArray history_specular;
#endif
uniform int svgf_step;
uniform bool svgf_write_history;

#ifndef SVGF_KERNEL
#define SVGF_KERNEL 5
#endif
#if SVGF_KERNEL == 3
const int RADIUS = 1;
const float KERNEL[2] = float[2](1.0 / 2.0, 1.0 / 4.0);
#elif SVGF_KERNEL == 5
const int RADIUS = 2;
const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
#else
#error SVGF_KERNEL must be 3 or 5
#endif
const float LOG2E = 1.4426950408889634;

// this frame's depth gradient per pixel (the variance stage's, rg16f)
uniform sampler2DArray gradient_cur;

// The variance at p blurred by a 3x3 Gaussian (x diffuse, y specular): a steadier luminance scale.
// A neighbour without a surface of its own to filter counts with variance 0: the reprojection
// wrote 0 there or, with SVGF_SHARED, left it unwritten and the key says so.
vec2 blurred_variance(ivec3 p, ivec2 size) {
    vec2 sum = vec2(0.0);
    float total = 0.0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            ivec3 q = p + ivec3(dx, dy, 0);
            if (!svgf_inside(q.xy, size)) continue;
            float k = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
            total += k;
#if SVGF_SHARED
            if (!(dx == 0 && dy == 0) && !(svgf_key_depth(texelFetch(key_cur, q, 0).xy) > 0.0)) continue;
#endif
            sum += k * svgf_illum_variance(texelFetch(src_illum, q, 0));
        }
    return sum / total;
}

// The centre pixel and the sums its taps add to.
float c_depth;
vec3 c_n;
vec2 c_lum, lum_scale;
vec2 sum_w, sum_v;
vec3 sum_d, sum_s;

// Adds the tap at q: `depth_scale` is -log2(e) over the depth weight's denominator for its offset,
// `log_k` log2 of its kernel weight. Every weight is one exp2 of a sum of exponents (depth,
// normal, luminance: the same product as svgf_weight_depth * svgf_weight_normal * exp(-|dl| / phi)),
// which spends half the special-function work of evaluating the factors one by one.
void add_tap(ivec3 q, ivec2 size, float depth_scale, float log_k) {
    if (!svgf_inside(q.xy, size)) return;
    uvec2 key = texelFetch(key_cur, q, 0).xy;
    float tap_depth = svgf_key_depth(key);
    if (!(tap_depth > 0.0)) return;   // no geometry: weight 0
    float e = abs(c_depth - tap_depth) * depth_scale + log_k;
    if (svgf_phi_normal > 0.0) {
        float c = dot(c_n, oct_unpack_snorm16(key.y));
        if (!(c > 0.0)) return;   // weight 0
        e += svgf_phi_normal * log2(c);
    }
    SvgfIllum tap = texelFetch(src_illum, q, 0);
    vec4 qd = svgf_illum_diffuse(tap);
    float wd = exp2(e - abs(c_lum.x - luminance(qd.rgb)) * lum_scale.x);
    sum_w.x += wd;
    sum_d += wd * qd.rgb;
    sum_v.x += wd * wd * qd.a;
#if SVGF_SPECULAR
    vec4 qs = svgf_illum_specular(tap);
    float ws = exp2(e - abs(c_lum.y - luminance(qs.rgb)) * lum_scale.y);
    sum_w.y += ws;
    sum_s += ws * qs.rgb;
    sum_v.y += ws * ws * qs.a;
#endif
}

void main() {
    ivec3 size = OUT_SIZE;
    ivec3 p;
    if (!svgf_pixel(size, p)) return;
    uvec2 key = texelFetch(key_cur, p, 0).xy;
    c_depth = svgf_key_depth(key);
    // nothing to filter: no tap reads this pixel's scratch texels (the variance blur reads the
    // reprojection's 0 or tests the key), nor its history, so only the last iteration writes, the background where nothing was drawn (a pixel
    // with another view's light gets it from svgf_spread.comp; over the list no such pixel comes
    // here, and svgf_spread.comp writes the background too)
    if (!(c_depth > 0.0)) {
#if SVGF_FINAL
#if SVGF_SHARED
        if (decision_spread(decision_at(p))) return;
#endif
        imageStore(dst, p, svgf_background(svgf_diffuse_in, p));
#endif
        return;
    }
    SvgfIllum centre = texelFetch(src_illum, p, 0);
    c_n = oct_unpack_snorm16(key.y);
    vec4 d = svgf_illum_diffuse(centre), s = svgf_illum_specular(centre);
    {
        vec2 phi = svgf_phi_color * sqrt(max(blurred_variance(p, size.xy), 0.0) + 1e-10);
        vec2 gradient = texelFetch(gradient_cur, p, 0).xy;
        lum_scale = LOG2E / phi;
        float depth_eps = 1e-3 * c_depth + 1e-8;
        float grad_step = svgf_phi_depth * float(svgf_step);
        c_lum = vec2(luminance(d.rgb), luminance(s.rgb));
        float k0 = KERNEL[0] * KERNEL[0];
        sum_w = vec2(k0);
        sum_d = k0 * d.rgb;
        sum_s = k0 * s.rgb;
        sum_v = k0 * k0 * vec2(d.a, s.a);
        // one half of the offsets (dy > 0, or dy 0 and dx > 0), each with its mirror
        for (int dy = 0; dy <= RADIUS; ++dy)
            for (int dx = -RADIUS; dx <= RADIUS; ++dx) {
                if (dy == 0 && dx <= 0) continue;
                float depth_scale = -LOG2E / (grad_step * abs(gradient.x * float(dx) + gradient.y * float(dy)) + depth_eps);
                float log_k = log2(KERNEL[abs(dx)] * KERNEL[dy]);
                ivec3 o = ivec3(dx * svgf_step, dy * svgf_step, 0);
                add_tap(p + o, size.xy, depth_scale, log_k);
                add_tap(p - o, size.xy, depth_scale, log_k);
            }
        d = vec4(sum_d / sum_w.x, sum_v.x / (sum_w.x * sum_w.x));
        s = vec4(sum_s / sum_w.y, sum_v.y / (sum_w.y * sum_w.y));
    }
#if SVGF_FINAL
    imageStore(dst, p, vec4(to_half_range(svgf_color(p, d.rgb, s.rgb)), 1.0));
#endif
#if !SVGF_FINAL || SVGF_SHARED
    imageStore(dst_illum, p, svgf_illum_pack(d, s));
#endif
    if (svgf_write_history) imageStore(history_diffuse, p, vec4(d.rgb, 0.0));
#if SVGF_SPECULAR
    if (svgf_write_history) imageStore(history_specular, p, vec4(s.rgb, 0.0));
#endif
}
