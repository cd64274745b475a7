// Lobe BSDF_LOBE_GLASS (bsdf_lobes.glsl): a rough dielectric interface (Walter et al. 2007):
// reflection and refraction through the microfacet by the exact Fresnel term (total internal
// reflection included), tinted by the base colour; thin-walled without a volume (the transmitted
// lobe mirrors the reflected one through the surface, no bending). Compensated by 1 / E_ss
// (bsdf_set_view's glass_comp_v: an approximation for the transmitted part).
//
// Sampled as Walter's section 5.3 and Mitsuba 3's roughdielectric: a visible normal m, then
// reflection about m with the probability of its Fresnel term F(v.m) (1 under total internal
// reflection), refraction through m (thin walls: the reflection mirrored through the surface)
// otherwise. The Fresnel term at the macro normal would starve transmission inside rough glass
// beyond the critical angle, where most microfacets still refract (weights of ~50 from a 2% floor).
// Its reflection rides on the GGX reflection term that bsdf.glsl shares among the reflecting lobes.
#pragma once
#include "bsdf_terms.glsl"

// Glass's Fresnel at a microfacet with cosine c to v: the exact term, scaled as glTF's specular
// and specular colour scale the dielectric's (equal to glTF's f0 at normal incidence, its f90 at
// grazing, 1 under total internal reflection when specular and its colour are 1).
vec3 bsdf_glass_fresnel(BsdfParams b, float c) {
    return b.specular * min(b.specular_color * fresnel_dielectric(c, bsdf_eta(b)), vec3(1.0));
}

void bsdf_glass_set_view(inout BsdfParams b) {
    b.glass_comp_v = b.ess_v;
#if SCENE_HAS_TRANSMISSION
    if (b.transmission > 0.0 && b.metallic < 1.0 && !b.thin)
        b.glass_comp_v = bsdf_glass_albedo(b.nv, b.roughness, b.ior, b.inside);
#endif
}

// The half vector of a transmission from v to l below the surface (thin: of the mirrored l),
// facing n; false when no microfacet connects them.
bool bsdf_transmission_half(BsdfParams b, vec3 n, vec3 v, vec3 l, out vec3 h) {
    if (b.thin) {
        h = normalize(v + (l - 2.0 * dot(n, l) * n));
        return true;
    }
    float eta = bsdf_eta(b);
    h = -normalize(v + eta * l);   // Walter et al. eq. 16
    if (dot(h, n) < 0.0) h = -h;
    return dot(v, h) > 0.0 && dot(l, h) < 0.0;
}

// f |n.l| of glass's transmitted lobe, for l below the surface.
vec3 bsdf_glass_eval_below(BsdfParams b, vec3 n, vec3 v, vec3 l) {
#if SCENE_HAS_TRANSMISSION
    float nv = dot(n, v), anl = -dot(n, l);
    vec3 w = bsdf_weights(b);
    if (nv <= 0.0 || anl <= 0.0 || w.y <= 0.0 || bsdf_is_delta(b)) return vec3(0.0);
    float eta = bsdf_eta(b);
    if (!b.thin && abs(eta - 1.0) < 1e-4) return vec3(0.0);   // index-matched: a delta straight through
    vec3 h;
    if (!bsdf_transmission_half(b, n, v, l, h)) return vec3(0.0);
    float alpha = bsdf_alpha(b);
    // thin walls: the reflected lobe mirrored, compensated as reflection is; volumes: the glass table
    float comp = b.glass_comp_v;
    float vh = dot(v, h);
    float g2 = 1.0 / (1.0 + smith_lambda(nv, sin2_between(n, v), alpha) + smith_lambda(anl, sin2_between(n, l), alpha));
    float d = ggx_d(dot(n, h), sin2_between(n, h), alpha);
    float f;
    if (b.thin) {
        f = d * g2 / (4.0 * nv * anl);            // the reflected lobe, mirrored through the surface
    } else {
        // Walter's BTDF for radiance: |vh lh| D G (1 - F) / (nv |nl| (vh + eta lh)^2), which
        // carries pbrt's 1 / eta^2 for radiance crossing into another medium
        float lh = dot(l, h);
        float denom = vh + eta * lh;
        f = abs(vh * lh) * d * g2 / (nv * anl * denom * denom);
    }
    return w.y * b.base_color * (vec3(1.0) - bsdf_glass_fresnel(b, vh)) * (f / comp * anl);
#else
    return vec3(0.0);
#endif
}

// An index-matched volume (eta 1): its transmission is a delta straight through at any roughness.
bool bsdf_index_matched(BsdfParams b) { return !b.thin && abs(bsdf_eta(b) - 1.0) < 1e-4; }

// The probability that glass's lobe reflects at a microfacet whose cosine to v is c: its Fresnel
// term (glTF's scaled one, bsdf_glass_fresnel; its mean over RGB for a coloured specular, so that
// both branches' weights stay within 3x of a white glass's). 0 when index-matched (the
// transmission is a delta there, the reflection's F ~ 0 is left to light sampling).
float bsdf_glass_reflect_probability(BsdfParams b, float c) {
#if SCENE_HAS_TRANSMISSION
    if (bsdf_index_matched(b)) return 0.0;
    vec3 f = bsdf_glass_fresnel(b, c);
    return clamp((f.x + f.y + f.z) * (1.0 / 3.0), 0.0, 1.0);
#else
    return 0.0;
#endif
}

// Glass lobe's probability of reflecting towards l above: F(v.h) at l's half vector.
float bsdf_glass_reflect_probability_to(BsdfParams b, vec3 v, vec3 l) {
#if SCENE_HAS_TRANSMISSION
    return bsdf_glass_reflect_probability(b, max(dot(v, normalize(v + l)), 0.0));
#else
    return 0.0;
#endif
}

// Solid-angle pdf of glass's lobe refracting (thin: passing, mirrored) to l below the surface:
// (1 - F(v.h)) D_v(h) times the Jacobian of h to l, eta^2 |l.h| / (v.h + eta l.h)^2 (Walter et
// al. eq. 17) for a refraction, 1 / (4 v.h) for a thin wall's mirrored reflection.
float bsdf_pdf_transmission(BsdfParams b, vec3 n, vec3 v, vec3 l) {
#if SCENE_HAS_TRANSMISSION
    if (bsdf_is_delta(b) || dot(n, l) >= 0.0 || bsdf_index_matched(b)) return 0.0;
    vec3 h;
    if (!bsdf_transmission_half(b, n, v, l, h)) return 0.0;
    float vh = dot(v, h);
    float pass = (1.0 - bsdf_glass_reflect_probability(b, vh)) * bsdf_vndf_pdf(b, n, v, h);
    if (b.thin) return pass / (4.0 * max(vh, 1e-8));
    float eta = bsdf_eta(b);
    float lh = dot(l, h);
    float denom = vh + eta * lh;
    return pass * eta * eta * abs(lh) / (denom * denom);
#else
    return 0.0;
#endif
}

// What its smooth transmission carries (roughness below BSDF_DELTA_ROUGHNESS).
vec3 bsdf_glass_delta_transmittance(BsdfParams b, float nv) {
    // radiance refracted into another medium scales by 1 / eta^2 (as the rough lobe's BTDF does)
    float eta = b.thin ? 1.0 : bsdf_eta(b);
    return bsdf_weights(b).y * b.base_color * (vec3(1.0) - bsdf_glass_fresnel(b, nv)) / (eta * eta);
}

// The lobe's reflection or transmission from u and u_split in [0,1) (see above); `q` its
// probability of the reflection it chose against (F at the microfacet; at n for a delta).
// False when it has none (l on the wrong side, total internal reflection in the transmission
// branch of a glass whose F stays below 1).
bool bsdf_glass_sample(BsdfParams b, vec3 n, vec3 v, vec2 u, float u_split, inout vec3 l, inout bool delta,
                       inout bool transmitted, inout float q) {
#if SCENE_HAS_TRANSMISSION
    bool matched = bsdf_index_matched(b);
    delta = bsdf_is_delta(b);
    vec3 h = delta ? n : bsdf_sample_vndf(b, n, v, u);
    q = bsdf_glass_reflect_probability(b, dot(v, h));
    if (u_split < q) {
        l = reflect(-v, h);
        return dot(n, l) > 0.0;
    }
    transmitted = true;
    if (matched || (delta && b.thin)) {   // straight through
        delta = true;
        l = -v;
        return true;
    }
    if (b.thin) {
        vec3 r = reflect(-v, h);
        l = r - 2.0 * dot(n, r) * n;
    } else {
        l = refract(-v, h, 1.0 / bsdf_eta(b));
        if (dot(l, l) == 0.0) return false;   // total internal reflection (F < 1: glTF's specular < 1)
    }
    return dot(n, l) < 0.0;
#else
    return false;
#endif
}

void bsdf_glass_add_fresnel(BsdfParams b, float vh, inout vec3 fresnel) {
    vec3 w = bsdf_weights(b);
    if (w.y > 0.0)   // compensated over its reflected and transmitted energy together
        fresnel += w.y * bsdf_glass_fresnel(b, vh) / b.glass_comp_v;
}

// Its reflected share (Fresnel at n.v) and its transmitted one (the rest, tinted by the base colour).
void bsdf_glass_add_albedo(BsdfParams b, inout vec3 reflected, inout vec3 transmitted) {
    float w = bsdf_weights(b).y;
    vec3 f = bsdf_glass_fresnel(b, b.nv);
    reflected += w * f;
    transmitted += w * b.base_color * max(vec3(1.0) - f, vec3(0.0));
}
