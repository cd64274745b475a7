// A ray pass's last dispatch when it reads a trace decision (fill.py): every pixel it did not trace
// takes the light traced this frame at its source (glsl/decision_taps.glsl), in the same images. The
// light is demodulated by each source pixel's directional albedos (glsl/demodulation.glsl,
// seen from its view) and remodulated by the pixel's own, so texture detail and the lobes' change
// with the view angle stay the pixel's; emission is each pixel's own.
// Images fill0..fill<FILL_IMAGES - 1>, each of format FILL<i>_FORMAT holding lobe FILL<i>_LOBE:
// 0 the whole light (emission + both lobes), 1 the diffuse lobe, 2 the specular lobe. With
// FILL_COLOR_FROM_LOBES fill0 is instead the pixel's emission + its filled fill1 + fill2. Pixels of
// effect below FILL_MIN_EFFECT are not this pass's, nor are pixels flagged DECISION_SPREAD (SVGF's).
#define GBUF_READER 1
#define TRACE_DECISION 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "demodulation.glsl"
#include "decision_taps.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(FILL0_FORMAT) uniform image2DArray fill0;
#if FILL_IMAGES > 1
layout(FILL1_FORMAT) uniform image2DArray fill1;
#endif
#if FILL_IMAGES > 2
layout(FILL2_FORMAT) uniform image2DArray fill2;
#endif

struct Albedos { vec3 diffuse; vec3 specular; vec3 emissive; };

Albedos albedos_of(GSurface g, uint view) {
    Albedos a;
    surface_albedos(g, view, a.diffuse, a.specular);
    a.emissive = g.emissive;
    return a;
}

vec3 lobe_albedo(Albedos a, int lobe) { return lobe == 0 ? a.diffuse + a.specular : (lobe == 1 ? a.diffuse : a.specular); }

// Light of `lobe` without the albedos (and the emission) of the surface it left.
vec3 demodulate_lobe(vec3 light, int lobe, Albedos a) {
    return demodulate(lobe == 0 ? light - a.emissive : light, lobe_albedo(a, lobe));
}

vec3 remodulate_lobe(vec3 illumination, int lobe, Albedos a) {
    vec3 r = remodulate(illumination, lobe_albedo(a, lobe));
    return lobe == 0 ? r + a.emissive : r;
}

struct Gathered { vec3 l0; vec3 l1; vec3 l2; };   // weighted by the taps' weights, which sum to 1

void gather(inout Gathered g, ivec3 q, float w) {
    Albedos a = albedos_of(gbuf_load(q), uint(q.z));
#if !FILL_COLOR_FROM_LOBES
    g.l0 += w * demodulate_lobe(imageLoad(fill0, q).rgb, FILL0_LOBE, a);
#endif
#if FILL_IMAGES > 1
    g.l1 += w * demodulate_lobe(imageLoad(fill1, q).rgb, FILL1_LOBE, a);
#endif
#if FILL_IMAGES > 2
    g.l2 += w * demodulate_lobe(imageLoad(fill2, q).rgb, FILL2_LOBE, a);
#endif
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(fill0);
    if (any(greaterThanEqual(p, size))) return;
    uvec2 t = decision_at(p);
    uint kind = decision_kind(t);
    if (kind < DECISION_REUSE || decision_spread(t)) return;   // flagged: SVGF writes it
    uint effect = gbuf_effect_at(p);
    if (effect == GBUF_NO_GEOMETRY || effect < uint(FILL_MIN_EFFECT)) return;
    GSurface surface = gbuf_load(p);
    DecisionTaps taps = decision_taps(decision_tested_taps(p, t, surface));
    Gathered g = Gathered(vec3(0.0), vec3(0.0), vec3(0.0));
    for (int k = 0; k < 4; ++k) {
        if (taps.w[k] > 0.0) gather(g, taps.q[k], taps.w[k]);
    }
    Albedos to = albedos_of(surface, uint(p.z));
#if FILL_IMAGES > 1
    vec3 f1 = remodulate_lobe(g.l1, FILL1_LOBE, to);
    imageStore(fill1, p, vec4(to_half_range(f1), 1.0));
#endif
#if FILL_IMAGES > 2
    vec3 f2 = remodulate_lobe(g.l2, FILL2_LOBE, to);
    imageStore(fill2, p, vec4(to_half_range(f2), 1.0));
#endif
#if FILL_COLOR_FROM_LOBES
    vec3 f0 = to.emissive + f1 + f2;
#else
    vec3 f0 = remodulate_lobe(g.l0, FILL0_LOBE, to);
#endif
    imageStore(fill0, p, vec4(to_half_range(f0), 1.0));
}
