// SVGF stage 2, variance estimation: pixels with a history of SVGF_MIN_HISTORY frames or more keep
// the temporal variance of their moments; younger ones (disoccluded, or the first frames) take
// the variance of the moments of a 7x7 neighbourhood weighted by depth and normal, boosted by
// 4 / history (section 4.2), in place in the reprojection's illumination texel. Their illumination
// stays their own: the a-trous stage filters it. With `svgf_write_history` (no feedback from an
// a-trous iteration) the temporal mean is also next frame's colour history.
#define SVGF_READS_SURFACE 1
#include "svgf_common.glsl"

#define SVGF_GROUP 8
layout(local_size_x = SVGF_GROUP, local_size_y = SVGF_GROUP, local_size_z = 1) in;

// in place: a pixel reads and writes its own texel only, and only young ones write
layout(SVGF_ILLUM_FORMAT) uniform SVGF_ILLUM_IMAGE illum;
layout(rgba16f) writeonly uniform image2DArray history_diffuse;
#if SVGF_SPECULAR
layout(rgba16f) writeonly uniform image2DArray history_specular;
#endif
uniform sampler2DArray moments_cur;
uniform bool svgf_write_history;

// A workgroup with a young pixel loads its 8x8 pixels' keys and moments with a 3-pixel apron
// into shared memory once (196 texels for 64 pixels, instead of 49 a young pixel); texels outside
// the view or without geometry hold key 0. Groups without one load nothing.
#define SVGF_APRON 3
#define SVGF_TILE (SVGF_GROUP + 2 * SVGF_APRON)
shared uvec2 tile_key[SVGF_TILE * SVGF_TILE];
shared vec4 tile_moments[SVGF_TILE * SVGF_TILE];
shared bool group_young;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(illum);
    bool young = false;
    SvgfSurface c;
    SvgfIllum centre;
    if (all(lessThan(p, size))) {
        c = svgf_unpack(texelFetch(key_cur, p, 0).xy, texelFetch(surface_cur, p, 0).xy);
        centre = imageLoad(illum, p);
        if (svgf_write_history) {   // the temporal mean as it is, before any spatial filter
            imageStore(history_diffuse, p, vec4(svgf_illum_diffuse(centre).rgb, 0.0));
#if SVGF_SPECULAR
            imageStore(history_specular, p, vec4(svgf_illum_specular(centre).rgb, 0.0));
#endif
        }
        young = c.depth > 0.0 && c.history < SVGF_MIN_HISTORY;   // else the temporal variance
    }
    if (gl_LocalInvocationIndex == 0u) group_young = false;
    barrier();
    if (young) group_young = true;
    barrier();
    if (!group_young) return;   // the whole workgroup
    ivec2 origin = ivec2(gl_WorkGroupID.xy) * SVGF_GROUP - SVGF_APRON;
    for (int i = int(gl_LocalInvocationIndex); i < SVGF_TILE * SVGF_TILE; i += SVGF_GROUP * SVGF_GROUP) {
        ivec3 q = ivec3(origin + ivec2(i % SVGF_TILE, i / SVGF_TILE), p.z);
        uvec2 key = svgf_inside(q.xy, size.xy) ? texelFetch(key_cur, q, 0).xy : uvec2(0u);
        tile_key[i] = key;
        tile_moments[i] = svgf_key_depth(key) > 0.0 ? texelFetch(moments_cur, q, 0) : vec4(0.0);
    }
    barrier();
    if (!young) return;
    int at = (int(gl_LocalInvocationID.y) + SVGF_APRON) * SVGF_TILE + int(gl_LocalInvocationID.x) + SVGF_APRON;
    vec2 gradient = svgf_depth_gradient(c.depth, svgf_key_depth(tile_key[at - 1]), svgf_key_depth(tile_key[at + 1]),
                                        svgf_key_depth(tile_key[at - SVGF_TILE]), svgf_key_depth(tile_key[at + SVGF_TILE]));
    float sum_w = 0.0;
    vec4 sum_m = vec4(0.0);
    for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx) {
            int t = at + dy * SVGF_TILE + dx;
            float depth = svgf_key_depth(tile_key[t]);
            if (!(depth > 0.0)) continue;   // nothing drawn there, or outside the view
            float w = svgf_weight_depth(c.depth, depth, gradient, vec2(dx, dy))
                      * svgf_weight_normal(c.n, svgf_unpack_normal(tile_key[t].y));
            sum_w += w;
            sum_m += w * tile_moments[t];
        }
    // the centre tap has weight 1, so sum_w >= 1
    vec4 m = sum_m / sum_w;
    // one sample's variance, boosted for the young history (x 4 / history) and divided as the
    // temporal estimate is by the frames averaged
    vec2 variance = max(vec2(m.y - m.x * m.x, m.w - m.z * m.z), 0.0) * (SVGF_MIN_HISTORY / (c.history * c.history));
    imageStore(illum, p, svgf_illum_pack(vec4(svgf_illum_diffuse(centre).rgb, variance.x),
                                         vec4(svgf_illum_specular(centre).rgb, variance.y)));
}
