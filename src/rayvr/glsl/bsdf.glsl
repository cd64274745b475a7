// The one BSDF of rayvr, shared by the raster lighting and every ray pass: glTF 2.0's
// metallic-roughness material (the specification's Appendix B) with KHR_materials_ior,
// _specular, _transmission and _volume, and energy compensation for single-scatter GGX.
//
//   material   = mix(mix(dielectric, glass, transmission), metal, metallic)
//   metal      = GGX specular with Schlick Fresnel on the base colour (f90 = 1)
//   dielectric = GGX specular with Schlick Fresnel f0 = min(((ior-1)/(ior+1))^2 specular_colour, 1)
//                x specular, f90 = specular, over a Lambert base weighted by what the specular
//                layer leaves: (1 - E(mu_v)) (1 - E(mu_l)) / (1 - E_avg) base / pi (E: the layer's
//                directional albedo; Kulla & Conty 2017's albedo scaling, which makes Appendix B's
//                "(1 - F) diffuse" conserve energy exactly; max over RGB as KHR_materials_specular
//                prescribes for a coloured F0)
//   glass      = rough dielectric interface (Walter et al. 2007): reflection and refraction
//                through the microfacet by the exact Fresnel term (total internal reflection
//                included), tinted by the base colour; thin-walled without a volume (the
//                transmitted lobe mirrors the reflected one through the surface, no bending).
//                Sampled as Walter's section 5.3: a visible normal m, then reflection with
//                probability F(v.m), refraction otherwise (bsdf_sample_lobe)
// Single-scatter GGX loses energy at high roughness: the specular lobes are scaled by
// 1 + f0 (1 / E_ss - 1) (Turquin 2019; exact for white metal) and glass by 1 / E_ss (an
// approximation for the transmitted part). E comes from rayvr/materials/bsdf_tables.py's tables.
// Roughness below BSDF_DELTA_ROUGHNESS is a delta lobe (mirror, straight refraction).
//
// Conventions: n, v, l unit vectors in one space; v points away from the surface on the side
// n faces (shading normals face the viewer); l away from it on either side (transmission: below).
// eval returns f(v, l) |n.l| (radiance per unit incoming radiance), without delta lobes.
//   BsdfParams bsdf_params(MaterialParams m)             the BSDF of a material (scene.glsl)
//   bsdf_set_side(inout b, bool inside)                  v inside the volume (a back face hit)
//   bsdf_set_view(inout b, n, v)                         caches what depends on v alone (the
//                                                        tables at n.v, the lobes' probabilities);
//                                                        call it last, before eval/pdf/sample,
//                                                        which take the same n and v
//   vec3  bsdf_eval(b, n, v, l)                          f |cos|
//   float bsdf_pdf(b, n, v, l)                           solid-angle pdf of bsdf_sample's non-delta lobes
//   float bsdf_pdf_specular(b, n, v, l)                  the same of bsdf_sample_specular, l above
//                                                        (its reflections: glass's share included)
//   bool  bsdf_sample(b, n, v, u, out BsdfSample)        u in [0,1)^3
//   bsdf_albedo(b, n, v, out diffuse, out specular)      directional albedos of the two parts
#pragma once
#include "sampling.glsl"
#include "color.glsl"
#include "scene.glsl"

layout(std430, binding = RAYVR_BSDF_TABLE_SSBO) readonly buffer BsdfTables {
    vec4 bsdf_table_info;   // mu size, roughness size, mu min, IOR size
    float bsdf_table[];     // A, B per (roughness, mu); Ā, B̄, C̄, D̄ per roughness; glass per (side, IOR, roughness, mu)
};

const float BSDF_DELTA_ROUGHNESS = MATERIAL_DELTA_ROUGHNESS;   // below it lobes are deltas (scene.glsl)
const float BSDF_MIN_ALPHA = 1e-6;         // BSDF_DELTA_ROUGHNESS^2

struct BsdfParams {
    vec3 base_color;
    float metallic;
    float roughness;       // perceptual; alpha = roughness^2
    float transmission;
    vec3 f0;               // dielectric F0 (ior, specular colour, specular)
    float f90;             // dielectric F90 (specular)
    vec3 specular_color;
    float specular;
    float ior;             // the material's index of refraction (outside: 1)
    bool thin;             // thin-walled transmission (no volume)
    bool inside;           // v is inside the volume (bsdf_set_side)
    // bsdf_set_view's cache: n.v, the tables' A and B there, the compensations of the specular
    // and glass lobes (1 / E_ss-like divisors), the dielectric layer's albedo at n.v and its
    // hemispherical average, the lobes' sampling probabilities
    float nv;
    vec2 ab_v;
    float ess_v;
    float glass_comp_v;
    float layer_v;
    float layer_avg;
    vec3 lobe_p;
};

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
    b.lobe_p = vec3(1.0, 0.0, 0.0);
    return b;
}

// Whether v lies inside the material's volume (the ray hit a back face): refraction then goes
// from the material's index to 1.
void bsdf_set_side(inout BsdfParams b, bool inside) { b.inside = inside && !b.thin; }

float bsdf_alpha(BsdfParams b) { return max(b.roughness * b.roughness, BSDF_MIN_ALPHA); }
bool bsdf_is_delta(BsdfParams b) { return b.roughness < BSDF_DELTA_ROUGHNESS; }
bool bsdf_is_mirror(BsdfParams b) { return bsdf_is_delta(b); }
// Relative index of refraction, the side of l over the side of v, for a refraction.
float bsdf_eta(BsdfParams b) { return b.inside ? 1.0 / b.ior : b.ior; }

// ---- tables -----------------------------------------------------------------------------------
// A and B (bsdf_tables.py) at cos(theta_v) = mu, bilinear in (mu, roughness).
vec2 bsdf_table_ab(float mu, float roughness) {
    int nm = int(bsdf_table_info.x), nr = int(bsdf_table_info.y);
    float mu_min = bsdf_table_info.z;
    float fx = clamp((mu - mu_min) / (1.0 - mu_min), 0.0, 1.0) * float(nm - 1);
    float fy = clamp(roughness, 0.0, 1.0) * float(nr - 1);
    int x0 = min(int(fx), nm - 2), y0 = min(int(fy), nr - 2);
    float tx = fx - float(x0), ty = fy - float(y0);
    int i00 = 2 * (y0 * nm + x0), i10 = i00 + 2 * nm;
    vec2 a = mix(vec2(bsdf_table[i00], bsdf_table[i00 + 1]), vec2(bsdf_table[i00 + 2], bsdf_table[i00 + 3]), tx);
    vec2 c = mix(vec2(bsdf_table[i10], bsdf_table[i10 + 1]), vec2(bsdf_table[i10 + 2], bsdf_table[i10 + 3]), tx);
    return mix(a, c, ty);
}

// Ā, B̄, C̄, D̄ at a roughness.
vec4 bsdf_table_averages(float roughness) {
    int nm = int(bsdf_table_info.x), nr = int(bsdf_table_info.y);
    int base = 2 * nm * nr;
    float fy = clamp(roughness, 0.0, 1.0) * float(nr - 1);
    int y0 = min(int(fy), nr - 2);
    float ty = fy - float(y0);
    vec4 a = vec4(bsdf_table[base + 4 * y0], bsdf_table[base + 4 * y0 + 1], bsdf_table[base + 4 * y0 + 2],
                  bsdf_table[base + 4 * y0 + 3]);
    vec4 c = vec4(bsdf_table[base + 4 * y0 + 4], bsdf_table[base + 4 * y0 + 5], bsdf_table[base + 4 * y0 + 6],
                  bsdf_table[base + 4 * y0 + 7]);
    return mix(a, c, ty);
}

const float BSDF_TABLE_IOR_MAX = 3.0;

// Glass's single-scatter albedo (bsdf_tables.py glass_tables) at (mu, roughness, ior), entering
// the glass or leaving it; trilinear.
float bsdf_glass_albedo(float mu, float roughness, float ior, bool leaving) {
    int nm = int(bsdf_table_info.x), nr = int(bsdf_table_info.y), ni = int(bsdf_table_info.w);
    int base = 2 * nm * nr + 4 * nr + (leaving ? ni * nr * nm : 0);
    float fx = clamp((mu - bsdf_table_info.z) / (1.0 - bsdf_table_info.z), 0.0, 1.0) * float(nm - 1);
    float fy = clamp(roughness, 0.0, 1.0) * float(nr - 1);
    float fz = clamp((ior - 1.0) / (BSDF_TABLE_IOR_MAX - 1.0), 0.0, 1.0) * float(ni - 1);
    int x0 = min(int(fx), nm - 2), y0 = min(int(fy), nr - 2), z0 = min(int(fz), ni - 2);
    float tx = fx - float(x0), ty = fy - float(y0), tz = fz - float(z0);
    float v[4];
    for (int k = 0; k < 4; ++k) {
        int z = z0 + (k >> 1), y = y0 + (k & 1);
        int i = base + (z * nr + y) * nm + x0;
        v[k] = mix(bsdf_table[i], bsdf_table[i + 1], tx);
    }
    return max(mix(mix(v[0], v[1], ty), mix(v[2], v[3], ty), tz), 1e-3);
}

// Albedo of the GGX lobe without Fresnel, E_ss(mu).
float bsdf_ess(vec2 ab) { return max(ab.x + ab.y, 1e-4); }

// Directional albedo of the compensated specular lobe with Schlick Fresnel (f0, f90).
vec3 bsdf_layer_albedo(vec3 f0, float f90, vec2 ab) {
    float ess = bsdf_ess(ab);
    return (f0 * ab.x + f90 * ab.y) * (1.0 + f0 * (1.0 / ess - 1.0));
}

// Its cosine-weighted hemispherical mean for a scalar f0.
float bsdf_layer_average(float f0, float f90, vec4 avg) {
    return f0 * avg.x + f90 * avg.y + f0 * f0 * avg.z + f0 * f90 * avg.w;
}

// ---- microfacet terms -------------------------------------------------------------------------
vec3 fresnel_schlick(vec3 f0, float f90, float cos_theta) {
    float m = clamp(1.0 - cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (vec3(f90) - f0) * (m2 * m2 * m);
}

vec3 fresnel_schlick(vec3 f0, float cos_theta) { return fresnel_schlick(f0, 1.0, cos_theta); }

// Exact unpolarised Fresnel reflectance of a dielectric interface, eta = n_transmitted / n_incident;
// 1 under total internal reflection.
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Glass's Fresnel at a microfacet with cosine c to v: the exact term, scaled as glTF's specular
// and specular colour scale the dielectric's (equal to glTF's f0 at normal incidence, its f90 at
// grazing, 1 under total internal reflection when specular and its colour are 1).
vec3 bsdf_glass_fresnel(BsdfParams b, float c) {
    return b.specular * min(b.specular_color * fresnel_dielectric(c, bsdf_eta(b)), vec3(1.0));
}

// GGX D from the cosine and the squared sine of n.h (the sine from a cross product: exact near
// n = h, where 1 - cos^2 cancels away tiny alphas).
float ggx_d(float cos_h, float sin2_h, float alpha) {
    float a2 = alpha * alpha;
    float d = a2 * cos_h * cos_h + sin2_h;
    return a2 / max(RAYVR_PI * d * d, 1e-36);
}

float smith_lambda(float cos_x, float sin2_x, float alpha) {
    float c2 = max(cos_x * cos_x, 1e-12);
    return 0.5 * (sqrt(1.0 + alpha * alpha * sin2_x / c2) - 1.0);
}

float sin2_between(vec3 a, vec3 b) { vec3 c = cross(a, b); return dot(c, c); }

// ---- lobe weights -----------------------------------------------------------------------------
// (w_dielectric, w_glass, w_metal): the mix of the three BSDFs.
vec3 bsdf_weights(BsdfParams b) {
    return vec3((1.0 - b.metallic) * (1.0 - b.transmission), (1.0 - b.metallic) * b.transmission, b.metallic);
}

// The dielectric's specular layer albedo at mu (max over RGB) and its average.
float bsdf_dielectric_layer(BsdfParams b, vec2 ab) { return max3(bsdf_layer_albedo(b.f0, b.f90, ab)); }

// ---- the lobes, evaluated ------------------------------------------------------------------
// f |n.l| of the specular reflections (dielectric layer, metal, glass), for l above the surface.
vec3 bsdf_eval_reflection(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    float nv = dot(n, v), nl = dot(n, l);
    if (nv <= 0.0 || nl <= 0.0 || bsdf_is_delta(b)) return vec3(0.0);
    vec3 w = bsdf_weights(b);
    float alpha = bsdf_alpha(b);
    float ess_v = b.ess_v;
    vec3 h = normalize(v + l);
    float vh = max(dot(v, h), 0.0);
    float g2 = 1.0 / (1.0 + smith_lambda(nv, sin2_between(n, v), alpha) + smith_lambda(nl, sin2_between(n, l), alpha));
    float fss = ggx_d(max(dot(n, h), 0.0), sin2_between(n, h), alpha) * g2 / (4.0 * nv * nl);
    vec3 fresnel = w.x * fresnel_schlick(b.f0, b.f90, vh) * (1.0 + b.f0 * (1.0 / ess_v - 1.0))
                 + w.z * fresnel_schlick(b.base_color, vh) * (1.0 + b.base_color * (1.0 / ess_v - 1.0));
    if (w.y > 0.0)   // glass, compensated over its reflected and transmitted energy together
        fresnel += w.y * bsdf_glass_fresnel(b, vh) / b.glass_comp_v;
    return fresnel * fss * nl;
}

// f |n.l| of the dielectric's Lambert base under its specular layer, for l above the surface.
vec3 bsdf_eval_diffuse(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    float nv = dot(n, v), nl = dot(n, l);
    vec3 w = bsdf_weights(b);
    if (nv <= 0.0 || nl <= 0.0 || w.x <= 0.0) return vec3(0.0);
    float el = b.f90 > 0.0 ? bsdf_dielectric_layer(b, bsdf_table_ab(nl, b.roughness)) : 0.0;
    return w.x * b.base_color * ((1.0 - b.layer_v) * (1.0 - el) / max(1.0 - b.layer_avg, 1e-4) / RAYVR_PI * nl);
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
vec3 bsdf_eval_transmission(BsdfParams b, vec3 n, vec3 v, vec3 l) {
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

vec3 bsdf_eval(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    if (dot(n, l) > 0.0) return bsdf_eval_reflection(b, n, v, l) + bsdf_eval_diffuse(b, n, v, l);
    return bsdf_eval_transmission(b, n, v, l);
}

// ---- the lobes, sampled -----------------------------------------------------------------------
// Three lobes are chosen among by their probabilities at mu_v (bsdf_set_view): 0 the specular
// reflections of the dielectric layer and the metal, 1 the dielectric's Lambert base, 2 glass
// (its reflection and its transmission together). Glass splits between reflection and
// transmission per sampled microfacet m, as Walter et al. 2007 (section 5.3) and Mitsuba 3's
// roughdielectric do: m from the visible normals of v, reflection about m with the probability
// of its Fresnel term F(v.m) (1 under total internal reflection), refraction through m (thin
// walls: the reflection mirrored through the surface) otherwise. The Fresnel term at the macro
// normal would starve transmission inside rough glass beyond the critical angle, where most
// microfacets still refract (weights of ~50 from a 2% floor).

// Probabilities of the three lobes, from their albedos at mu_v. Every lobe that can carry light
// keeps at least a small share, so that MIS never meets a zero pdf where f > 0.
vec3 bsdf_lobe_probabilities_at(BsdfParams b, float nv, vec2 ab) {
    vec3 w = bsdf_weights(b);
    vec3 e_spec = bsdf_layer_albedo(b.f0, b.f90, ab);
    float fg = w.y > 0.0 ? max3(bsdf_glass_fresnel(b, nv)) : 0.0;
    float base = luminance(b.base_color);
    vec3 p = vec3(w.x * luminance(e_spec) + w.z * luminance(bsdf_layer_albedo(b.base_color, 1.0, ab)),
                  w.x * (1.0 - max3(e_spec)) * base,
                  w.y * (fg + (1.0 - fg) * base));
    bvec3 can = bvec3(w.z > 0.0 || (w.x > 0.0 && b.f90 > 0.0), w.x > 0.0 && base > 0.0,
                      w.y > 0.0 && (base > 0.0 || b.specular > 0.0));
    p = max(p, mix(vec3(0.0), vec3(0.02), can));
    float sum = p.x + p.y + p.z;
    return sum > 0.0 ? p / sum : vec3(1.0, 0.0, 0.0);
}

void bsdf_set_view(inout BsdfParams b, vec3 n, vec3 v) {
    b.nv = clamp(dot(n, v), 0.0, 1.0);
    b.ab_v = bsdf_table_ab(b.nv, b.roughness);
    b.ess_v = bsdf_ess(b.ab_v);
    b.glass_comp_v = b.ess_v;
#if SCENE_HAS_TRANSMISSION
    if (b.transmission > 0.0 && b.metallic < 1.0 && !b.thin)
        b.glass_comp_v = bsdf_glass_albedo(b.nv, b.roughness, b.ior, b.inside);
#endif
    b.layer_v = bsdf_dielectric_layer(b, b.ab_v);
    b.layer_avg = b.f90 > 0.0 ? bsdf_layer_average(max3(b.f0), b.f90, bsdf_table_averages(b.roughness)) : 0.0;
    b.lobe_p = bsdf_lobe_probabilities_at(b, b.nv, b.ab_v);
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

// Pdf of the GGX visible normal h for v: G1(v) max(v.h, 0) D(h) / n.v.
float bsdf_vndf_pdf(BsdfParams b, vec3 n, vec3 v, vec3 h) {
    float nv = dot(n, v);
    float alpha = bsdf_alpha(b);
    float g1 = 1.0 / (1.0 + smith_lambda(nv, sin2_between(n, v), alpha));
    return g1 * max(dot(v, h), 0.0) * ggx_d(max(dot(n, h), 0.0), sin2_between(n, h), alpha) / max(nv, 1e-8);
}

vec3 bsdf_sample_vndf(BsdfParams b, vec3 n, vec3 v, vec2 u) {
    mat3 tbn = basis_from_normal(n);
    vec3 vl = transpose(tbn) * v;
    return tbn * sample_ggx_vndf(normalize(vec3(vl.xy, max(vl.z, 1e-6))), bsdf_alpha(b), u);
}

// Solid-angle pdf of a reflection about a visible normal, D_v(h) / (4 v.h), for l above (non-delta).
float bsdf_pdf_reflection(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    if (bsdf_is_delta(b) || dot(n, l) <= 0.0) return 0.0;
    vec3 h = normalize(v + l);
    return bsdf_vndf_pdf(b, n, v, h) / (4.0 * max(dot(v, h), 1e-8));
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

// Pdf of bsdf_sample_lobes's direction l among the lobes of probabilities p (summing to 1).
float bsdf_pdf_lobes(BsdfParams b, vec3 n, vec3 v, vec3 l, vec3 p) {
    float nv = dot(n, v), nl = dot(n, l);
    if (nv <= 0.0 || nl == 0.0) return 0.0;
    if (nl < 0.0) return p.z * bsdf_pdf_transmission(b, n, v, l);
    float reflect_p = p.x;
#if SCENE_HAS_TRANSMISSION
    if (p.z > 0.0) reflect_p += p.z * bsdf_glass_reflect_probability_to(b, v, l);
#endif
    return reflect_p * bsdf_pdf_reflection(b, n, v, l) + p.y * nl / RAYVR_PI;
}

float bsdf_pdf(BsdfParams b, vec3 n, vec3 v, vec3 l) { return bsdf_pdf_lobes(b, n, v, l, b.lobe_p); }

// The lobe probabilities of bsdf_sample_specular: the diffuse lobe left out.
vec3 bsdf_specular_lobe_probabilities(BsdfParams b) {
    float sum = b.lobe_p.x + b.lobe_p.z;
    return sum > 0.0 ? vec3(b.lobe_p.x, 0.0, b.lobe_p.z) / sum : vec3(0.0);
}

// Solid-angle pdf of bsdf_sample_specular's direction l above the surface (its reflections:
// the reflection lobe and glass's reflecting share): what the direct-light passes weigh their
// light samples against.
float bsdf_pdf_specular(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    if (dot(n, l) <= 0.0) return 0.0;
    return bsdf_pdf_lobes(b, n, v, l, bsdf_specular_lobe_probabilities(b));
}

struct BsdfSample {
    vec3 l;             // sampled direction
    vec3 weight;        // f |cos| / pdf
    float pdf;          // solid angle, of the lobes the sampler chose among; 0 for a delta lobe
    bool delta;
    bool transmitted;   // l is below the surface (refracted or passed through)
};

// What the delta lobes (roughness below BSDF_DELTA_ROUGHNESS) carry: a mirror's and smooth
// glass's reflection, smooth glass's transmission.
vec3 bsdf_delta_reflectance(BsdfParams b, float nv) {
    vec3 w = bsdf_weights(b);
    return w.x * fresnel_schlick(b.f0, b.f90, nv) + w.z * fresnel_schlick(b.base_color, nv)
         + w.y * bsdf_glass_fresnel(b, nv);
}

vec3 bsdf_delta_transmittance(BsdfParams b, float nv) {
    // radiance refracted into another medium scales by 1 / eta^2 (as the rough lobe's BTDF does)
    float eta = b.thin ? 1.0 : bsdf_eta(b);
    return bsdf_weights(b).y * b.base_color * (vec3(1.0) - bsdf_glass_fresnel(b, nv)) / (eta * eta);
}

// A direction of lobe `lobe` (0 reflection, 1 diffuse, 2 glass) from u.xy (glass: u_split in
// [0,1) chooses between its reflection and transmission); `delta` when it is a delta there (then
// l is exact), `transmitted` when l is below; `q` glass's probability of the reflection it chose
// against (F at the microfacet; at n for a delta). False when it has none (l on the wrong side,
// total internal reflection in the transmission branch of a glass whose F stays below 1).
bool bsdf_sample_lobe(BsdfParams b, vec3 n, vec3 v, int lobe, vec2 u, float u_split, out vec3 l, out bool delta,
                      out bool transmitted, out float q) {
    delta = false;
    transmitted = false;
    q = 0.0;
    l = n;
    if (lobe == 0) {
        delta = bsdf_is_delta(b);
        l = reflect(-v, delta ? n : bsdf_sample_vndf(b, n, v, u));
        return dot(n, l) > 0.0;
    }
    if (lobe == 1) {
        l = basis_from_normal(n) * sample_cosine_hemisphere(u);
        return true;
    }
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

// One sample among the lobes (with or without the diffuse one), chosen by their probabilities;
// u.xy the direction, u.z the lobe (and, rescaled, glass's reflection or transmission). The
// weight is f / pdf over the chosen set (one-sample MIS between the lobes: bsdf_pdf_lobes), or
// the deltas' value in that direction over the probability of drawing it.
bool bsdf_sample_lobes(BsdfParams b, vec3 n, vec3 v, vec3 u, bool with_diffuse, out BsdfSample s) {
    s.delta = false;
    s.transmitted = false;
    s.pdf = 0.0;
    s.weight = vec3(0.0);
    s.l = n;
    float nv = dot(n, v);
    if (nv <= 0.0) return false;
    vec3 p = with_diffuse ? b.lobe_p : bsdf_specular_lobe_probabilities(b);
    if (!(p.x + p.y + p.z > 0.0)) return false;
    int lobe = u.z < p.x ? 0 : (u.z < p.x + p.y ? 1 : 2);
    float u_split = lobe == 2 ? clamp((u.z - p.x - p.y) / max(p.z, 1e-30), 0.0, 1.0) : 0.0;
    bool delta;
    float q;
    if (!bsdf_sample_lobe(b, n, v, lobe, u.xy, u_split, s.l, delta, s.transmitted, q)) return false;
    if (delta) {
        s.delta = true;
        // a smooth surface's mirror direction is drawn by the reflection lobe and glass's
        // reflection, its straight or refracted one by glass's transmission alone
        s.weight = s.transmitted ? bsdf_delta_transmittance(b, nv) / (p.z * (1.0 - q))
                                 : bsdf_delta_reflectance(b, nv) / (p.x + p.z * bsdf_glass_reflect_probability(b, nv));
        return max3(s.weight) > 0.0;
    }
    s.pdf = bsdf_pdf_lobes(b, n, v, s.l, p);
    vec3 f;
    if (s.transmitted)
        f = bsdf_eval_transmission(b, n, v, s.l);
    else
        f = bsdf_eval_reflection(b, n, v, s.l) + (with_diffuse ? bsdf_eval_diffuse(b, n, v, s.l) : vec3(0.0));
    if (!(s.pdf > 0.0)) return false;
    s.weight = f / s.pdf;
    return true;
}

// One sample of the whole BSDF (its pdf is bsdf_pdf's).
bool bsdf_sample(BsdfParams b, vec3 n, vec3 v, vec3 u, out BsdfSample s) {
    return bsdf_sample_lobes(b, n, v, u, true, s);
}

// One sample of the specular lobes alone (reflection and glass): what RTReflections traces, the
// diffuse part being lit by the direct-light passes. Its pdf above the surface is bsdf_pdf_specular's.
bool bsdf_sample_specular(BsdfParams b, vec3 n, vec3 v, vec3 u, out BsdfSample s) {
    return bsdf_sample_lobes(b, n, v, u, false, s);
}

// ---- albedos ----------------------------------------------------------------------------------
void bsdf_albedo(BsdfParams b, vec3 n, vec3 v, out vec3 diffuse, out vec3 specular) {
    vec3 w = bsdf_weights(b);
    float nv = b.nv;
    vec2 ab = b.ab_v;
    vec3 e_spec = bsdf_layer_albedo(b.f0, b.f90, ab);
    diffuse = w.x * b.base_color * (1.0 - max3(e_spec));
    specular = w.x * e_spec + w.z * bsdf_layer_albedo(b.base_color, 1.0, ab) + w.y * bsdf_glass_fresnel(b, nv);
}
