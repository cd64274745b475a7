// SVGF stage 3, one iteration of the edge-avoiding a-trous wavelet filter (section 4.3): a 5x5
// B3-spline kernel with taps `svgf_step` pixels apart, each weighted by depth (against the depth
// gradient), normal and luminance (against the 3x3 Gaussian of the variance); the variance is
// filtered with the squared weights. With `svgf_write_history` the result is next frame's history.
#define SVGF_READS_SURFACE 1
#include "svgf_common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

uniform sampler2DArray src_diffuse;
layout(rgba16f) writeonly uniform image2DArray dst_diffuse;
layout(rgba16f) writeonly uniform image2DArray history_diffuse;
#if SVGF_SPECULAR
uniform sampler2DArray src_specular;
layout(rgba16f) writeonly uniform image2DArray dst_specular;
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
            sum.x += k * texelFetch(src_diffuse, q, 0).a;
#if SVGF_SPECULAR
            sum.y += k * texelFetch(src_specular, q, 0).a;
#endif
            total += k;
        }
    return sum / total;
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(dst_diffuse);
    if (any(greaterThanEqual(p, size))) return;
    SvgfSurface c = svgf_unpack(texelFetch(surface_cur, p, 0));
    vec4 d = texelFetch(src_diffuse, p, 0);
    vec4 s = vec4(0.0);
#if SVGF_SPECULAR
    s = texelFetch(src_specular, p, 0);
#endif
    if (svgf_has_geometry(c.word)) {
        vec2 phi = svgf_phi_color * sqrt(max(blurred_variance(p, size.xy), 0.0) + 1e-10);
        vec2 gradient = svgf_depth_gradient(p, c.depth, size.xy);
        float ld = luminance(d.rgb), ls = luminance(s.rgb);
        float centre = KERNEL[0] * KERNEL[0];
        vec2 sum_w = vec2(centre);
        vec3 sum_d = centre * d.rgb, sum_s = centre * s.rgb;
        vec2 sum_v = centre * centre * vec2(d.a, s.a);
        for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
                if (dx == 0 && dy == 0) continue;
                vec2 offset = vec2(dx, dy) * float(svgf_step);
                ivec3 q = p + ivec3(ivec2(offset), 0);
                if (!svgf_inside(q.xy, size.xy)) continue;
                SvgfSurface t = svgf_unpack(texelFetch(surface_cur, q, 0));
                if (!svgf_has_geometry(t.word)) continue;
                float w = KERNEL[abs(dx)] * KERNEL[abs(dy)] * svgf_weight_depth(c.depth, t.depth, gradient, offset)
                          * svgf_weight_normal(c.n, t.n);
                vec4 qd = texelFetch(src_diffuse, q, 0);
                float wd = w * exp(-abs(ld - luminance(qd.rgb)) / phi.x);
                sum_w.x += wd;
                sum_d += wd * qd.rgb;
                sum_v.x += wd * wd * qd.a;
#if SVGF_SPECULAR
                vec4 qs = texelFetch(src_specular, q, 0);
                float ws = w * exp(-abs(ls - luminance(qs.rgb)) / phi.y);
                sum_w.y += ws;
                sum_s += ws * qs.rgb;
                sum_v.y += ws * ws * qs.a;
#endif
            }
        d = vec4(sum_d / sum_w.x, sum_v.x / (sum_w.x * sum_w.x));
        s = vec4(sum_s / sum_w.y, sum_v.y / (sum_w.y * sum_w.y));
    }
    imageStore(dst_diffuse, p, d);
    if (svgf_write_history) imageStore(history_diffuse, p, vec4(d.rgb, 0.0));
#if SVGF_SPECULAR
    imageStore(dst_specular, p, s);
    if (svgf_write_history) imageStore(history_specular, p, vec4(s.rgb, 0.0));
#endif
}
