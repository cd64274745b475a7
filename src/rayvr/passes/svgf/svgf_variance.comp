// SVGF stage 2, variance estimation: pixels with a history of SVGF_MIN_HISTORY frames or more keep
// the temporal variance of their moments; younger ones (disoccluded, or the first frames) take
// the variance of the moments of a 7x7 neighbourhood weighted by depth and normal, boosted by
// 4 / history (section 4.2), in place in the reprojection's illumination texel. Their illumination
// stays their own: the a-trous stage filters it. With `svgf_write_history` (no feedback from an
// a-trous iteration) the temporal mean is also next frame's colour history. Every pixel with
// geometry also writes its depth gradient (`gradient_out`), which depends on this frame's key
// only: the a-trous iterations fetch it instead of deriving it again each iteration.
#define SVGF_READS_SURFACE 1
#include "svgf_common.glsl"
#include "svgf_pixels.glsl"

// in place: a pixel reads and writes its own texel only, and only young ones write
layout(SVGF_ILLUM_FORMAT) uniform SVGF_ILLUM_IMAGE illum;
layout(rgba16f) writeonly uniform image2DArray history_diffuse;
#if SVGF_SPECULAR
layout(rgba16f) writeonly uniform image2DArray history_specular;
#endif
uniform sampler2DArray moments_cur;
// this frame's depth gradient, which the a-trous iterations read instead of four key fetches each
layout(rg16f) writeonly uniform image2DArray gradient_out;
uniform bool svgf_write_history;

void main() {
    ivec3 size = imageSize(illum);
    ivec3 p;
    if (!svgf_pixel(size, p)) return;
    uvec2 key = texelFetch(key_cur, p, 0).xy;
    // no geometry (or light another view's, svgf_spread.comp): nothing here is read again, neither
    // the gradient by the a-trous stage nor the history by the next reprojection (its length is 0)
    if (!(svgf_key_depth(key) > 0.0)) return;
    SvgfSurface c = svgf_unpack(key, texelFetch(surface_cur, p, 0).xy);
    SvgfIllum centre = imageLoad(illum, p);
    if (svgf_write_history) {   // the temporal mean as it is, before any spatial filter
        imageStore(history_diffuse, p, vec4(svgf_illum_diffuse(centre).rgb, 0.0));
#if SVGF_SPECULAR
        imageStore(history_specular, p, vec4(svgf_illum_specular(centre).rgb, 0.0));
#endif
    }
    vec2 gradient = svgf_depth_gradient(p, c.depth, size.xy);
    imageStore(gradient_out, p, vec4(svgf_gradient_store(gradient), 0.0, 0.0));
    if (c.history >= SVGF_MIN_HISTORY) return;   // the temporal variance
    float sum_w = 0.0;
    vec4 sum_m = vec4(0.0);
    for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx) {
            ivec3 q = p + ivec3(dx, dy, 0);
            float depth;
            vec3 n;
            if (!svgf_key_at(q, size.xy, depth, n)) continue;
            float w = svgf_weight_depth(c.depth, depth, gradient, vec2(dx, dy)) * svgf_weight_normal(c.n, n);
            sum_w += w;
            sum_m += w * texelFetch(moments_cur, q, 0);
        }
    // the centre tap has weight 1, so sum_w >= 1
    vec4 m = sum_m / sum_w;
    // one sample's variance, boosted for the young history (x 4 / history) and divided as the
    // temporal estimate is by the frames averaged
    vec2 variance = max(vec2(m.y - m.x * m.x, m.w - m.z * m.z), 0.0) * (SVGF_MIN_HISTORY / (c.history * c.history));
    imageStore(illum, p, svgf_illum_pack(vec4(svgf_illum_diffuse(centre).rgb, variance.x),
                                         vec4(svgf_illum_specular(centre).rgb, variance.y)));
}
