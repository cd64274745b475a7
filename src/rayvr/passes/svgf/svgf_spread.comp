// SVGF's last stage where a trace decision reuses light across views (SVGF_SHARED): every pixel
// whose light this frame is another view's (flagged DECISION_SPREAD: glsl/trace_decision.glsl) takes
// that view's filtered illumination over the traced pixels of its surface there
// (glsl/decision_taps.glsl), remodulated by its own albedos and emission. The reprojection wrote
// it as having no surface, so the variance and a-trous stages did no work for it. Its history is
// its sources': it is not copied here. The pixel keeps its own filter key, the history length
// SVGF_BORROWED and its decision texel with the taps tested (`spread_source`), and on a later
// frame where it traces its own light (the eyes alternating, a view moving off its source) the
// reprojection reads the sources' history through that texel. With SVGF_FILTER_LIST, where the a-trous stage ran over the
// pixels it filters only, it also writes the background where nothing was drawn.
#define TRACE_DECISION 1
#include "svgf_common.glsl"
#include "decision_taps.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

uniform SVGF_ILLUM_SAMPLER src_illum;   // this frame's filtered illumination (the last a-trous output)
#if SVGF_FILTER_LIST
uniform sampler2DArray svgf_diffuse_in;   // the background where nothing was drawn
#endif
layout(rgba16f) writeonly uniform image2DArray dst;
layout(rg32ui) writeonly uniform uimage2DArray key_cur;
layout(rg32ui) writeonly uniform uimage2DArray surface_cur;
layout(rg32ui) writeonly uniform uimage2DArray spread_source;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    uvec2 t = decision_at(p);
    if (!decision_spread(t)) {
#if SVGF_FILTER_LIST
        if (!svgf_has_geometry(gbuf_fetch_effect(p)))
            imageStore(dst, p, svgf_background(svgf_diffuse_in, p));
#endif
        return;
    }
    GSurface g = gbuf_load(p);
    t = decision_tested_taps(p, t, g);
    DecisionTaps taps = decision_taps(t);
    vec3 d = vec3(0.0), s = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        float w = taps.w[k];
        if (!(w > 0.0)) continue;
        SvgfIllum illum = texelFetch(src_illum, taps.q[k], 0);
        d += w * svgf_illum_diffuse(illum).rgb;
#if SVGF_SPECULAR
        s += w * svgf_illum_specular(illum).rgb;
#endif
    }
    imageStore(dst, p, vec4(to_half_range(svgf_color(g, uint(p.z), d, s)), 1.0));
    SvgfSurface own = svgf_surface_at(p, g, gbuf_fetch_effect(p), SVGF_BORROWED);
    imageStore(key_cur, p, uvec4(svgf_pack_key(own), 0u, 0u));
    imageStore(surface_cur, p, uvec4(svgf_pack_tag(own), 0u, 0u));
    imageStore(spread_source, p, uvec4(t, 0u, 0u));
}
