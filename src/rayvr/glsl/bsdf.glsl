// The one BSDF of rayvr, shared by the raster lighting and every ray pass: glTF 2.0's
// metallic-roughness material (the specification's Appendix B) with KHR_materials_ior,
// _specular, _transmission and _volume, and energy compensation for single-scatter GGX.
//
//   material   = mix(mix(dielectric, glass, transmission), metal, metallic)
//   metal      = GGX specular with Schlick Fresnel on the base colour (f90 = 1)
//   dielectric = GGX specular with Schlick Fresnel f0 = min(((ior-1)/(ior+1))^2 specular_colour, 1)
//                x specular, f90 = specular, over a Lambert base weighted by what the specular
//                layer leaves
//   glass      = rough dielectric interface (Walter et al. 2007), thin-walled without a volume
// as three lobes, a file each (bsdf_lobes.glsl): BSDF_LOBE_SPECULAR (the dielectric's layer and
// the metal), BSDF_LOBE_DIFFUSE (the Lambert base), BSDF_LOBE_GLASS (its reflection and
// transmission). The lobes that reflect through GGX (BSDF_LOBES_GGX) share its D G / (4 n.v n.l)
// and add their Fresnel factors. Single-scatter GGX loses energy at high roughness: the specular
// lobes are scaled by 1 + f0 (1 / E_ss - 1) (Turquin 2019; exact for white metal) and glass by
// 1 / E_ss. E comes from rayvr/materials/bsdf_tables.py's tables. Roughness below
// BSDF_DELTA_ROUGHNESS is a delta lobe (mirror, straight refraction).
//
// Conventions: n, v, l unit vectors in one space; v points away from the surface on the side
// n faces (shading normals face the viewer); l away from it on either side (transmission: below).
// eval returns f(v, l) |n.l| (radiance per unit incoming radiance), without delta lobes. `lobes`
// is a set of lobes (BSDF_LOBES_ALL, BSDF_LOBES_SPECULAR, BSDF_LOBES_DIFFUSE: bsdf_lobes.glsl).
//   BsdfParams bsdf_params(MaterialParams m)             the BSDF of a material (scene.glsl)
//   bsdf_set_side(inout b, bool inside)                  v inside the volume (a back face hit)
//   bsdf_set_view(inout b, n, v)                         caches what depends on v alone (the
//                                                        tables at n.v, the lobes' probabilities);
//                                                        call it last, before eval/pdf/sample,
//                                                        which take the same n and v
//   vec3  bsdf_eval_lobes(b, n, v, l, lobes)             f |cos| of the lobes
//   bool  bsdf_sample_lobes(b, n, v, u, lobes, out BsdfSample)   u in [0,1)^3: one sample of the
//                                                        lobes, chosen by their probabilities
//   float bsdf_pdf_lobes(b, n, v, l, lobes)              its solid-angle pdf (non-delta)
//   vec3  bsdf_eval(b, n, v, l), float bsdf_pdf(...), bool bsdf_sample(...)   all the lobes
//   float bsdf_pdf_specular(b, n, v, l), bool bsdf_sample_specular(...)       BSDF_LOBES_SPECULAR,
//                                                        l above (what a reflection pass traces)
//   bsdf_albedo(b, n, v, out diffuse, out specular)      directional albedos of the two parts
//   bsdf_albedo_parts(b, n, v, out diffuse, out reflected, out transmitted)   the second apart
#pragma once
#include "bsdf_lobes.glsl"

BsdfParams bsdf_params(MaterialParams m) {
    BsdfParams b;
    b.base_color = max(m.base_color, vec3(0.0));
    b.metallic = clamp(m.metallic, 0.0, 1.0);
    b.roughness = clamp(m.roughness, 0.0, 1.0);
    b.transmission = clamp(m.transmission, 0.0, 1.0);
    b.specular = clamp(m.specular, 0.0, 1.0);
    b.specular_color = max(m.specular_color, vec3(0.0));
    b.ior = max(m.ior, 1.0);
    float r = (b.ior - 1.0) / (b.ior + 1.0);
    b.f0 = min(vec3(r * r) * b.specular_color, vec3(1.0)) * b.specular;
    b.f90 = b.specular;
    b.thin = !m.volume;
    b.inside = false;
    b.nv = 0.0;
    b.ab_v = vec2(0.0);
    b.ess_v = 1.0;
    b.glass_comp_v = 1.0;
    b.layer_v = 0.0;
    b.layer_avg = 0.0;
    b.lobe_p = BsdfLobeFloats(0.0);
    b.lobe_p[BSDF_LOBE_FALLBACK] = 1.0;
    return b;
}

// Whether v lies inside the material's volume (the ray hit a back face): refraction then goes
// from the material's index to 1.
void bsdf_set_side(inout BsdfParams b, bool inside) { b.inside = inside && !b.thin; }

// ---- the lobes' probabilities -------------------------------------------------------------------
// Probabilities of the lobes at mu_v, from their weights (albedos). Every lobe that can carry
// light keeps at least a small share, so that MIS never meets a zero pdf where f > 0. The lobes
// are named here (components BSDF_LOBE_SPECULAR, _DIFFUSE, _GLASS), as in bsdf_pdf_of and
// bsdf_sample_lobes: see bsdf_lobes.glsl.
void bsdf_lobe_probabilities_at(BsdfParams b, float nv, vec2 ab, out BsdfLobeFloats p) {
    vec3 w = bsdf_weights(b);
    vec3 e_spec = bsdf_layer_albedo(b.f0, b.f90, ab);
    float fg = w.y > 0.0 ? max3(bsdf_glass_fresnel(b, nv)) : 0.0;
    float base = luminance(b.base_color);
    p = vec3(w.x * luminance(e_spec) + w.z * luminance(bsdf_layer_albedo(b.base_color, 1.0, ab)),
             w.x * (1.0 - max3(e_spec)) * base,
             w.y * (fg + (1.0 - fg) * base));
    bvec3 can = bvec3(w.z > 0.0 || (w.x > 0.0 && b.f90 > 0.0), w.x > 0.0 && base > 0.0,
                      w.y > 0.0 && (base > 0.0 || b.specular > 0.0));
    p = max(p, mix(vec3(0.0), vec3(0.02), can));
    float sum = p.x + p.y + p.z;
    p = sum > 0.0 ? p / sum : vec3(1.0, 0.0, 0.0);
}

void bsdf_set_view(inout BsdfParams b, vec3 n, vec3 v) {
    b.nv = clamp(dot(n, v), 0.0, 1.0);
    b.ab_v = bsdf_table_ab(b.nv, b.roughness);
    b.ess_v = bsdf_ess(b.ab_v);
    b.layer_v = bsdf_dielectric_layer(b, b.ab_v);
    b.layer_avg = b.f90 > 0.0 ? bsdf_layer_average(max3(b.f0), b.f90, bsdf_table_averages(b.roughness)) : 0.0;
    bsdf_glass_set_view(b);
    bsdf_lobe_probabilities_at(b, b.nv, b.ab_v, b.lobe_p);
}

// The probabilities of sampling among `lobes` alone: the set's share of bsdf_set_view's,
// renormalised (all 0 when none of them carries light).
void bsdf_lobe_probabilities(BsdfParams b, uint lobes, out BsdfLobeFloats p) {
    if (lobes == BSDF_LOBES_ALL) {
        p = b.lobe_p;
        return;
    }
    p = b.lobe_p * vec3(bsdf_lobe_in(lobes, BSDF_LOBE_SPECULAR), bsdf_lobe_in(lobes, BSDF_LOBE_DIFFUSE),
                        bsdf_lobe_in(lobes, BSDF_LOBE_GLASS));
    float sum = p.x + p.y + p.z;
    p = sum > 0.0 ? p / sum : vec3(0.0);
}

// ---- evaluation ---------------------------------------------------------------------------------
// f |n.l| of the GGX reflection of the reflecting lobes of `lobes`, for l above the surface.
vec3 bsdf_eval_ggx(BsdfParams b, vec3 n, vec3 v, vec3 l, uint lobes) {
    float nv = dot(n, v), nl = dot(n, l);
    if ((lobes & BSDF_LOBES_GGX) == 0u || nv <= 0.0 || nl <= 0.0 || bsdf_is_delta(b)) return vec3(0.0);
    float alpha = bsdf_alpha(b);
    vec3 h = normalize(v + l);
    float vh = max(dot(v, h), 0.0);
    float g2 = 1.0 / (1.0 + smith_lambda(nv, sin2_between(n, v), alpha) + smith_lambda(nl, sin2_between(n, l), alpha));
    float fss = ggx_d(max(dot(n, h), 0.0), sin2_between(n, h), alpha) * g2 / (4.0 * nv * nl);
    vec3 fresnel = vec3(0.0);
    if (bsdf_lobe_in(lobes, BSDF_LOBE_SPECULAR)) bsdf_specular_add_fresnel(b, vh, fresnel);
    if (bsdf_lobe_in(lobes, BSDF_LOBE_GLASS)) bsdf_glass_add_fresnel(b, vh, fresnel);
    return fresnel * fss * nl;
}

// f |n.l| of `lobes` for l on the side `above` says (the caller's: l's, or a sample's).
vec3 bsdf_eval_side(BsdfParams b, vec3 n, vec3 v, vec3 l, uint lobes, bool above) {
    if (above)
        return bsdf_eval_ggx(b, n, v, l, lobes)
             + (bsdf_lobe_in(lobes, BSDF_LOBE_DIFFUSE) ? bsdf_diffuse_eval_above(b, n, v, l) : vec3(0.0));
    return bsdf_lobe_in(lobes, BSDF_LOBE_GLASS) ? bsdf_glass_eval_below(b, n, v, l) : vec3(0.0);
}

vec3 bsdf_eval_lobes(BsdfParams b, vec3 n, vec3 v, vec3 l, uint lobes) {
    return bsdf_eval_side(b, n, v, l, lobes, dot(n, l) > 0.0);
}

vec3 bsdf_eval(BsdfParams b, vec3 n, vec3 v, vec3 l) { return bsdf_eval_lobes(b, n, v, l, BSDF_LOBES_ALL); }

// ---- sampling -----------------------------------------------------------------------------------
// Pdf of bsdf_sample_lobes's direction l among `lobes` of probabilities p (summing to 1; 0 for the
// lobes outside the set): the GGX reflection of the specular lobe and of glass's reflecting share,
// the diffuse lobe's cosine, glass's transmission below.
float bsdf_pdf_of(BsdfParams b, vec3 n, vec3 v, vec3 l, BsdfLobeFloats p, uint lobes) {
    float nv = dot(n, v), nl = dot(n, l);
    if (nv <= 0.0 || nl == 0.0) return 0.0;
    if (nl < 0.0) return p.z * bsdf_pdf_transmission(b, n, v, l);
    float reflect_p = p.x;
#if SCENE_HAS_TRANSMISSION
    if (p.z > 0.0) reflect_p += p.z * bsdf_glass_reflect_probability_to(b, v, l);
#endif
    return reflect_p * bsdf_pdf_reflection(b, n, v, l) + p.y * nl / RAYVR_PI;
}

float bsdf_pdf_lobes(BsdfParams b, vec3 n, vec3 v, vec3 l, uint lobes) {
    BsdfLobeFloats p;
    bsdf_lobe_probabilities(b, lobes, p);
    return bsdf_pdf_of(b, n, v, l, p, lobes);
}

float bsdf_pdf(BsdfParams b, vec3 n, vec3 v, vec3 l) { return bsdf_pdf_lobes(b, n, v, l, BSDF_LOBES_ALL); }

// Solid-angle pdf of bsdf_sample_specular's direction l above the surface (its reflections:
// the specular lobe and glass's reflecting share): what the direct-light passes weigh their
// light samples against.
float bsdf_pdf_specular(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    if (dot(n, l) <= 0.0) return 0.0;
    return bsdf_pdf_lobes(b, n, v, l, BSDF_LOBES_SPECULAR);
}

struct BsdfSample {
    vec3 l;             // sampled direction
    vec3 weight;        // f |cos| / pdf
    float pdf;          // solid angle, of the lobes the sampler chose among; 0 for a delta lobe
    bool delta;
    bool transmitted;   // l is below the surface (refracted or passed through)
};

// One sample among `lobes`, chosen by their probabilities; u.xy the direction, u.z the lobe (and,
// rescaled to the chosen lobe's interval, u_split: glass's reflection or transmission). The
// weight is f / pdf over the set (one-sample MIS between the lobes: bsdf_pdf_of), or the deltas'
// value in that direction over the probability of drawing it.
bool bsdf_sample_lobes(BsdfParams b, vec3 n, vec3 v, vec3 u, uint lobes, out BsdfSample s) {
    s.delta = false;
    s.transmitted = false;
    s.pdf = 0.0;
    s.weight = vec3(0.0);
    s.l = n;
    float nv = dot(n, v);
    if (nv <= 0.0) return false;
    BsdfLobeFloats p;
    bsdf_lobe_probabilities(b, lobes, p);
    if (!(p.x + p.y + p.z > 0.0)) return false;
    // the lobe whose interval of [0, 1) holds u.z (index order), and u.z rescaled to glass's
    int lobe = u.z < p.x ? BSDF_LOBE_SPECULAR : (u.z < p.x + p.y ? BSDF_LOBE_DIFFUSE : BSDF_LOBE_GLASS);
    float u_split = lobe == BSDF_LOBE_GLASS ? clamp((u.z - p.x - p.y) / max(p.z, 1e-30), 0.0, 1.0) : 0.0;
    bool delta = false;
    float q = 0.0;
    s.transmitted = false;
    bool ok;
    if (lobe == BSDF_LOBE_SPECULAR) ok = bsdf_specular_sample(b, n, v, u.xy, s.l, delta);
    else if (lobe == BSDF_LOBE_DIFFUSE) ok = bsdf_diffuse_sample(n, u.xy, s.l);
    else ok = bsdf_glass_sample(b, n, v, u.xy, u_split, s.l, delta, s.transmitted, q);
    if (!ok) return false;
    if (delta) {
        s.delta = true;
        // a smooth surface's mirror direction is drawn by the specular lobe and glass's reflection
        // (their delta reflectance over the probability of drawing it), its straight or refracted
        // one by glass's transmission alone
        vec3 w = bsdf_weights(b);
        s.weight = s.transmitted ? bsdf_glass_delta_transmittance(b, nv) / (p.z * (1.0 - q))
                                 : (w.x * fresnel_schlick(b.f0, b.f90, nv) + w.z * fresnel_schlick(b.base_color, nv)
                                    + w.y * bsdf_glass_fresnel(b, nv)) / (p.x + p.z * bsdf_glass_reflect_probability(b, nv));
        return max3(s.weight) > 0.0;
    }
    s.pdf = bsdf_pdf_of(b, n, v, s.l, p, lobes);
    vec3 f;
    if (s.transmitted)
        f = bsdf_glass_eval_below(b, n, v, s.l);
    else
        f = bsdf_eval_ggx(b, n, v, s.l, lobes)
          + (bsdf_lobe_in(lobes, BSDF_LOBE_DIFFUSE) ? bsdf_diffuse_eval_above(b, n, v, s.l) : vec3(0.0));
    if (!(s.pdf > 0.0)) return false;
    s.weight = f / s.pdf;
    return true;
}

// One sample of the whole BSDF (its pdf is bsdf_pdf's).
bool bsdf_sample(BsdfParams b, vec3 n, vec3 v, vec3 u, out BsdfSample s) {
    return bsdf_sample_lobes(b, n, v, u, BSDF_LOBES_ALL, s);
}

// One sample of the specular lobes alone (reflection and glass): what RTReflections traces, the
// diffuse part being lit by the direct-light passes. Its pdf above the surface is bsdf_pdf_specular's.
bool bsdf_sample_specular(BsdfParams b, vec3 n, vec3 v, vec3 u, out BsdfSample s) {
    return bsdf_sample_lobes(b, n, v, u, BSDF_LOBES_SPECULAR, s);
}

// ---- albedos ----------------------------------------------------------------------------------
// Directional albedos at bsdf_set_view's n.v: of the diffuse lobe, of the lobes that reflect
// (the specular layer, the metal, glass's reflection) and of glass's transmission.
void bsdf_albedo_parts(BsdfParams b, vec3 n, vec3 v, out vec3 diffuse, out vec3 reflected, out vec3 transmitted) {
    diffuse = vec3(0.0);
    reflected = vec3(0.0);
    transmitted = vec3(0.0);
    bsdf_specular_add_albedo(b, reflected);
    bsdf_diffuse_add_albedo(b, diffuse);
    bsdf_glass_add_albedo(b, reflected, transmitted);
}

// Of the diffuse lobe and of the rest, reflected and transmitted (what the denoisers demodulate by).
void bsdf_albedo(BsdfParams b, vec3 n, vec3 v, out vec3 diffuse, out vec3 specular) {
    vec3 transmitted;
    bsdf_albedo_parts(b, n, v, diffuse, specular, transmitted);
    specular += transmitted;
}
