// SVGF stage 3, one iteration of the edge-avoiding a-trous wavelet filter (section 4.3): a 5x5
// B3-spline kernel with taps `svgf_step` pixels apart, each weighted by depth (against the depth
// gradient), normal and luminance (against the 3x3 Gaussian of the variance); the variance is
// filtered with the squared weights. With `svgf_write_history` the result is next frame's history.
//
// Texture fetches are what this stage costs, so the workgroup first loads its 8x8 pixels of the
// filter key and the illumination with an apron into shared memory, once: an apron of 2 x step
// (every tap of the kernel) while the step is at most SVGF_TILE_MAX_STEP, else of 1 (the variance
// blur, the centre and the depth gradient's neighbours). Taps further out are fetched.
#define SVGF_READS_SURFACE 1
#include "svgf_common.glsl"

#define SVGF_GROUP 8
layout(local_size_x = SVGF_GROUP, local_size_y = SVGF_GROUP, local_size_z = 1) in;

uniform SVGF_ILLUM_SAMPLER src_illum;
layout(SVGF_ILLUM_FORMAT) writeonly uniform SVGF_ILLUM_IMAGE dst_illum;
layout(rgba16f) writeonly uniform image2DArray history_diffuse;
#if SVGF_SPECULAR
layout(rgba16f) writeonly uniform image2DArray history_specular;
#endif
uniform int svgf_step;
uniform bool svgf_write_history;

const float KERNEL[3] = float[3](3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);

#ifndef SVGF_TILE_MAX_STEP
#define SVGF_TILE_MAX_STEP 2
#endif
#if SVGF_TILE_MAX_STEP > 0
#define SVGF_TILE_MAX (SVGF_GROUP + 4 * SVGF_TILE_MAX_STEP)
#else
#define SVGF_TILE_MAX (SVGF_GROUP + 2)
#endif
// The tile, row by row; texels outside the view hold key 0 (no geometry) and illumination 0.
shared uvec2 tile_key[SVGF_TILE_MAX * SVGF_TILE_MAX];
shared SvgfIllum tile_illum[SVGF_TILE_MAX * SVGF_TILE_MAX];

void store_history(ivec3 p, vec4 d, vec4 s) {
    if (!svgf_write_history) return;
    imageStore(history_diffuse, p, vec4(d.rgb, 0.0));
#if SVGF_SPECULAR
    imageStore(history_specular, p, vec4(s.rgb, 0.0));
#endif
}

void main() {
    ivec3 size = imageSize(dst_illum);
    bool tiled = svgf_step <= SVGF_TILE_MAX_STEP;   // the same for the whole dispatch
    int apron = tiled ? 2 * svgf_step : 1;
    int width = SVGF_GROUP + 2 * apron;
    ivec2 origin = ivec2(gl_WorkGroupID.xy) * SVGF_GROUP - apron;
    int layer = int(gl_WorkGroupID.z);
    for (int i = int(gl_LocalInvocationIndex); i < width * width; i += SVGF_GROUP * SVGF_GROUP) {
        ivec3 q = ivec3(origin + ivec2(i % width, i / width), layer);
        bool inside = svgf_inside(q.xy, size.xy);
        tile_key[i] = inside ? texelFetch(key_cur, q, 0).xy : uvec2(0u);
        tile_illum[i] = inside ? texelFetch(src_illum, q, 0) : SvgfIllum(0);
    }
    barrier();

    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, size))) return;
    int at = (int(gl_LocalInvocationID.y) + apron) * width + int(gl_LocalInvocationID.x) + apron;
    SvgfIllum centre = tile_illum[at];
    vec4 d = svgf_illum_diffuse(centre), s = svgf_illum_specular(centre);
    float depth = svgf_key_depth(tile_key[at]);
    if (!(depth > 0.0)) {   // nothing drawn: the texel as it came
        imageStore(dst_illum, p, centre);
        store_history(p, d, s);
        return;
    }
    vec3 n = svgf_unpack_normal(tile_key[at].y);
    vec2 gradient = svgf_depth_gradient(depth, svgf_key_depth(tile_key[at - 1]), svgf_key_depth(tile_key[at + 1]),
                                        svgf_key_depth(tile_key[at - width]), svgf_key_depth(tile_key[at + width]));

    // the variance blurred by a 3x3 Gaussian over the pixels inside the view (x diffuse, y
    // specular): a steadier luminance scale
    vec2 variance = vec2(0.0);
    float total = 0.0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            if (!svgf_inside(p.xy + ivec2(dx, dy), size.xy)) continue;
            float k = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
            variance += k * svgf_illum_variance(tile_illum[at + dy * width + dx]);
            total += k;
        }
    vec2 phi = svgf_phi_color * sqrt(max(variance / total, 0.0) + 1e-10);

    float ld = luminance(d.rgb), ls = luminance(s.rgb);
    float k0 = KERNEL[0] * KERNEL[0];
    vec2 sum_w = vec2(k0);
    vec3 sum_d = k0 * d.rgb, sum_s = k0 * s.rgb;
    vec2 sum_v = k0 * k0 * vec2(d.a, s.a);
    for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
            if (dx == 0 && dy == 0) continue;
            vec2 offset = vec2(dx, dy) * float(svgf_step);
            ivec3 q = p + ivec3(ivec2(offset), 0);
            int t = at + (dy * width + dx) * svgf_step;
            uvec2 key = tiled ? tile_key[t] : (svgf_inside(q.xy, size.xy) ? texelFetch(key_cur, q, 0).xy : uvec2(0u));
            float tap_depth = svgf_key_depth(key);
            if (!(tap_depth > 0.0)) continue;   // nothing drawn there, or outside the view
            float w = KERNEL[abs(dx)] * KERNEL[abs(dy)] * svgf_weight_depth(depth, tap_depth, gradient, offset)
                      * svgf_weight_normal(n, svgf_unpack_normal(key.y));
            SvgfIllum tap = tiled ? tile_illum[t] : texelFetch(src_illum, q, 0);
            vec4 qd = svgf_illum_diffuse(tap);
            float wd = w * exp(-abs(ld - luminance(qd.rgb)) / phi.x);
            sum_w.x += wd;
            sum_d += wd * qd.rgb;
            sum_v.x += wd * wd * qd.a;
#if SVGF_SPECULAR
            vec4 qs = svgf_illum_specular(tap);
            float ws = w * exp(-abs(ls - luminance(qs.rgb)) / phi.y);
            sum_w.y += ws;
            sum_s += ws * qs.rgb;
            sum_v.y += ws * ws * qs.a;
#endif
        }
    d = vec4(sum_d / sum_w.x, sum_v.x / (sum_w.x * sum_w.x));
    s = vec4(sum_s / sum_w.y, sum_v.y / (sum_w.y * sum_w.y));
    imageStore(dst_illum, p, svgf_illum_pack(d, s));
    store_history(p, d, s);
}
