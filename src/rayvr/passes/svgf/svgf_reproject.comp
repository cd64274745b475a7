// SVGF stage 1, reprojection and temporal accumulation, every view in one dispatch (layer z of
// every history texture is view z). This frame's lobes are demodulated by their albedos; the
// history of last frame's filtered illumination is fetched where the G-buffer's motion vector
// says this surface was (bilinear over the taps that pass the disocclusion test, else the mean
// of the 3x3 taps that do), blended with weight max(alpha, 1 / history length), and the
// luminance moments are accumulated the same way (moments_alpha); the variance follows from them.
// With TRACE_DECISION a pixel's ray budget b (glsl/trace_decision.glsl: the share of frames its own
// rays are traced) stretches its history: the new frame weighs b times as much and the history may
// grow 1 / b times as long, so a sparsely traced pixel averages about as many of its own samples
// as a dense one; and the variance is that of b x history samples, which widens the filter there.
// With SVGF_SHARED a pixel flagged DECISION_SPREAD (its light is another view's) is left to
// svgf_spread.comp: here it is written as having no surface, so the variance and a-trous stages
// neither filter it nor take it as a tap; a tap of last frame that was such a pixel (history
// length SVGF_BORROWED) gives its sources' history, through its decision texel, and the scratch
// texels of pixels without a surface are left unwritten: the variance blur tests the key before it
// reads one. Without SVGF_SHARED they are written 0 (few pixels, and no key test in the blur's
// nine taps at every pixel). With SVGF_FILTER_LIST it lists the pixels it does filter, those the
// later stages run over (svgf_pixels.glsl).
#include "svgf_common.glsl"
#include "trace_decision.glsl"
#if SVGF_SHARED
#include "decision_taps.glsl"
#endif
#define SVGF_LIST_WRITER 1
#include "svgf_pixels.glsl"

uniform sampler2DArray svgf_diffuse_in;
uniform sampler2DArray history_diffuse;
#if SVGF_SPECULAR
uniform sampler2DArray svgf_specular_in;
uniform sampler2DArray history_specular;
#endif
layout(SVGF_ILLUM_FORMAT) writeonly uniform SVGF_ILLUM_IMAGE out_illum;   // both lobes + variances
#if !SVGF_SHARED
layout(SVGF_ILLUM_FORMAT) writeonly uniform SVGF_ILLUM_IMAGE out_illum_other;   // the other scratch texture
#endif
uniform sampler2DArray moments_prev;
uniform usampler2DArray key_prev;
uniform usampler2DArray surface_prev;
layout(rgba32f) writeonly uniform image2DArray moments_out;
layout(rg32ui) writeonly uniform uimage2DArray key_out;
layout(rg32ui) writeonly uniform uimage2DArray surface_out;

uniform float svgf_alpha;           // weight of this frame's illumination (at least 1 / history)
uniform float svgf_moments_alpha;   // the same for the moments
uniform float svgf_max_history;
uniform float svgf_still_max_history;   // the cap of a pixel that did not move on a still frame
uniform bool svgf_still;            // this frame's views and scene are last frame's (passes/history.py)
uniform bool svgf_history_valid;    // false on the first frame and after a scene edit
#if SVGF_SHARED
uniform usampler2DArray spread_source;   // last frame's decision texel where svgf_spread.comp wrote
#endif

// The history this pixel reprojects to, summed over the taps of last frame that show its surface.
struct Reprojected {
    float weight;
    vec3 diffuse;
    vec3 specular;
    vec4 moments;
    float history;
};

// The history of last frame's pixel q (`history` frames long) with weight w.
void add_history(inout Reprojected r, ivec3 q, float w, float history) {
    r.weight += w;
    r.diffuse += w * texelFetch(history_diffuse, q, 0).rgb;
#if SVGF_SPECULAR
    r.specular += w * texelFetch(history_specular, q, 0).rgb;
#endif
    r.moments += w * texelFetch(moments_prev, q, 0);
    r.history += w * history;
}

#if SVGF_SHARED
// The history of a pixel q that borrowed its light last frame: its sources' (the traced pixels its
// decision texel names, each with a history of its own), weighted as the spread weighed them.
void add_borrowed_history(inout Reprojected r, ivec3 q, float w) {
    DecisionTaps taps = decision_taps(texelFetch(spread_source, q, 0).xy);
    float history[4];
    float total = 0.0;
    for (int k = 0; k < 4; ++k) {
        history[k] = taps.w[k] > 0.0 ? uintBitsToFloat(texelFetch(surface_prev, taps.q[k], 0).y) : 0.0;
        if (history[k] > 0.0) total += taps.w[k];
    }
    if (!(total > 0.0)) return;
    for (int k = 0; k < 4; ++k)
        if (history[k] > 0.0) add_history(r, taps.q[k], w * taps.w[k] / total, history[k]);
}
#endif

void add_tap(inout Reprojected r, ivec3 q, float w, uint word, vec3 n, float prev_depth, float tolerance) {
    if (w <= 0.0 || !svgf_inside(q.xy, textureSize(key_prev, 0).xy)) return;
    SvgfSurface s = svgf_unpack(texelFetch(key_prev, q, 0).xy, texelFetch(surface_prev, q, 0).xy);
    bool borrowed = SVGF_SHARED != 0 && s.history == SVGF_BORROWED;
    if (!(s.history > 0.0 || borrowed) || !reprojection_matches(s.depth, s.n, s.word, prev_depth, n, word, tolerance))
        return;
#if SVGF_SHARED
    if (borrowed) {
        add_borrowed_history(r, q, w);
        return;
    }
#endif
    add_history(r, q, w, s.history);
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(out_illum);
    bool inside = all(lessThan(p, size));
    uint word = inside ? gbuf_fetch_effect(p) : 0u;
    bool borrowed = false;
#if SVGF_SHARED
    borrowed = inside && decision_spread(decision_at(p));
#endif
    svgf_list_pixel(inside && svgf_has_geometry(word) && !borrowed, p);
    if (!inside) return;
    if (!svgf_has_geometry(word) || borrowed) {
        // the key says "no surface": no a-trous tap reads this pixel; the variance blur reads its
        // scratch texels (0) or, with SVGF_SHARED, tests the key first; a borrowed pixel's tag is
        // svgf_spread.comp's to write (its moments are its sources'), and nothing reads it before
#if !SVGF_SHARED
        SvgfIllum zero = svgf_illum_pack(vec4(0.0), vec4(0.0));
        imageStore(out_illum, p, zero);
        imageStore(out_illum_other, p, zero);
#endif
        SvgfSurface none = svgf_no_geometry();
        imageStore(key_out, p, uvec4(svgf_pack_key(none), 0u, 0u));
        if (borrowed) return;
        imageStore(moments_out, p, vec4(0.0));
        imageStore(surface_out, p, uvec4(svgf_pack_tag(none), 0u, 0u));
        return;
    }
    GSurface g = gbuf_load(p);
    vec3 albedo_d, albedo_s;
    svgf_albedos(g, uint(p.z), albedo_d, albedo_s);
    vec3 diffuse = svgf_demodulate(texelFetch(svgf_diffuse_in, p, 0).rgb, albedo_d);
    vec3 specular = vec3(0.0);
#if SVGF_SPECULAR
    specular = svgf_demodulate(texelFetch(svgf_specular_in, p, 0).rgb, albedo_s);
#endif
    float depth = gbuf_fetch_posW(p).w;
    vec2 gradient = gbuf_depth_gradient(p, depth, size.xy);

    Reprojected r = Reprojected(0.0, vec3(0.0), vec3(0.0), vec4(0.0), 0.0);
    if (svgf_history_valid) {
        // where this surface point was in last frame's view, and the depth it had there
        vec2 prev = reprojected_pixel(p);
        float prev_depth = reprojected_depth(uint(p.z), g.pos);
        float tolerance = reprojection_tolerance(prev_depth, gradient);
        vec2 b = prev - 0.5;
        ivec2 base = ivec2(floor(b));
        vec2 f = b - vec2(base);
        add_tap(r, ivec3(base, p.z), (1.0 - f.x) * (1.0 - f.y), word, g.n, prev_depth, tolerance);
        add_tap(r, ivec3(base + ivec2(1, 0), p.z), f.x * (1.0 - f.y), word, g.n, prev_depth, tolerance);
        add_tap(r, ivec3(base + ivec2(0, 1), p.z), (1.0 - f.x) * f.y, word, g.n, prev_depth, tolerance);
        add_tap(r, ivec3(base + ivec2(1, 1), p.z), f.x * f.y, word, g.n, prev_depth, tolerance);
        if (r.weight < 1e-3) {   // no bilinear tap survived: the 3x3 around the nearest pixel
            r = Reprojected(0.0, vec3(0.0), vec3(0.0), vec4(0.0), 0.0);
            ivec2 nearest = ivec2(floor(prev));
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    add_tap(r, ivec3(nearest + ivec2(dx, dy), p.z), 1.0, word, g.n, prev_depth, tolerance);
        }
    }
    bool found = r.weight >= 1e-3;
    // a pixel that did not move on a still frame sees last frame's surface under the same light:
    // its history is an exact running mean (alpha 1 / length), so its variance, and with it the
    // a-trous filter, falls towards zero as the still view converges
    bool still = found && svgf_still && dot(gbuf_fetch_motion(p), gbuf_fetch_motion(p)) < 1e-6;
    float density = 1.0;
#if TRACE_DECISION
    density = max(decision_density(p), 1.0 / 255.0);
#endif
    float history = found ? min(r.history / r.weight + 1.0, still ? svgf_still_max_history : svgf_max_history / density)
                          : 1.0;
    float alpha = found ? (still ? 1.0 / history : max(svgf_alpha * density, 1.0 / history)) : 1.0;
    float moments_alpha = found ? (still ? 1.0 / history : max(svgf_moments_alpha * density, 1.0 / history)) : 1.0;
    float inv = found ? 1.0 / r.weight : 0.0;
    float ld = luminance(diffuse), ls = luminance(specular);
    vec4 moments = mix(r.moments * inv, vec4(ld, ld * ld, ls, ls * ls), moments_alpha);
    // the moments' variance is that of one frame's sample; the colour averages about `samples`
    // frames (1 / alpha's exponential window once the history is long), whose mean has
    // 1 / samples of it: the filter then backs off as the history grows, and a still view
    // converges to the temporal mean instead of staying blurred
    float samples = (still ? history : min(history, (2.0 - alpha) / alpha)) * density;
    vec2 variance = max(vec2(moments.y - moments.x * moments.x, moments.w - moments.z * moments.z), 0.0) / samples;
    imageStore(out_illum, p, svgf_illum_pack(vec4(to_half_range(mix(r.diffuse * inv, diffuse, alpha)), variance.x),
                                             vec4(to_half_range(mix(r.specular * inv, specular, alpha)), variance.y)));
    imageStore(moments_out, p, moments);
    SvgfSurface s = svgf_surface_at(p, g, word, history);
    imageStore(key_out, p, uvec4(svgf_pack_key(s), 0u, 0u));
    imageStore(surface_out, p, uvec4(svgf_pack_tag(s), 0u, 0u));
}
