// The one metallic-roughness BSDF, shared by the raster lighting and every ray pass: Lambert
// diffuse + GGX specular with height-correlated Smith masking and Schlick Fresnel, the choice
// between its lobes, and importance sampling with the matching pdf.
// Conventions: n, v, l unit vectors in one space, v and l point away from the surface;
// eval returns f(v, l) * max(dot(n, l), 0) (radiance per unit incoming radiance).
//   BsdfParams bsdf_params(MaterialParams m)       the BSDF of a material (scene.glsl)
//   vec3  bsdf_eval(b, n, v, l)                     f * cos
//   float bsdf_pdf(b, n, v, l)                      solid-angle pdf of bsdf_sample choosing l
//   bool  bsdf_sample(b, n, v, u, out BsdfSample)   u in [0,1)^3
#pragma once
#include "sampling.glsl"
#include "color.glsl"
#include "scene.glsl"

struct BsdfParams {
    vec3 base_color;
    float metallic;
    float roughness;    // perceptual; alpha = roughness^2
};

// The BSDF of material parameters m (metallic and roughness clamped to [0, 1]).
BsdfParams bsdf_params(MaterialParams m) {
    BsdfParams b;
    b.base_color = m.base_color;
    b.metallic = clamp(m.metallic, 0.0, 1.0);
    b.roughness = clamp(m.roughness, 0.0, 1.0);
    return b;
}

// Below this alpha the lobe is treated as a perfect mirror (avoids D -> inf and NaN at roughness 0).
const float BSDF_MIN_ALPHA = 1e-3;

float bsdf_alpha(BsdfParams p) { return max(p.roughness * p.roughness, BSDF_MIN_ALPHA); }
bool bsdf_is_mirror(BsdfParams p) { return p.roughness * p.roughness < BSDF_MIN_ALPHA * 4.0; }
vec3 bsdf_f0(BsdfParams p) { return mix(vec3(0.04), p.base_color, p.metallic); }
vec3 bsdf_diffuse_albedo(BsdfParams p) { return p.base_color * (1.0 - p.metallic); }

vec3 fresnel_schlick(vec3 f0, float cos_theta) {
    float m = clamp(1.0 - cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

float ggx_d(float n_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_h * n_h * (a2 - 1.0) + 1.0;
    return a2 / max(RAYVR_PI * d * d, 1e-12);
}

float smith_lambda(float n_x, float alpha) {
    float c2 = max(n_x * n_x, 1e-8);
    float t2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

float smith_g1(float n_x, float alpha) { return 1.0 / (1.0 + smith_lambda(n_x, alpha)); }

float smith_g2(float n_v, float n_l, float alpha) {
    return 1.0 / (1.0 + smith_lambda(n_v, alpha) + smith_lambda(n_l, alpha));
}

// Diffuse part of eval: Lambert with the diffuse albedo (base colour times 1 - metallic; no
// Fresnel weighting).
vec3 bsdf_eval_diffuse(BsdfParams p, vec3 n, vec3 v, vec3 l) {
    float n_l = dot(n, l);
    if (n_l <= 0.0) return vec3(0.0);
    return bsdf_diffuse_albedo(p) * (n_l / RAYVR_PI);
}

// Specular part of eval (GGX microfacet); zero for mirrors, whose light arrives by reflection rays.
vec3 bsdf_eval_specular(BsdfParams p, vec3 n, vec3 v, vec3 l) {
    float n_l = dot(n, l);
    float n_v = dot(n, v);
    if (n_l <= 0.0 || n_v <= 0.0 || bsdf_is_mirror(p)) return vec3(0.0);
    vec3 h = normalize(v + l);
    float alpha = bsdf_alpha(p);
    vec3 f = fresnel_schlick(bsdf_f0(p), max(dot(v, h), 0.0));
    float spec = ggx_d(max(dot(n, h), 0.0), alpha) * smith_g2(n_v, n_l, alpha) / (4.0 * n_v);
    return f * spec;   // already times n_l: (D G F / 4 n_v n_l) * n_l
}

vec3 bsdf_eval(BsdfParams p, vec3 n, vec3 v, vec3 l) {
    return bsdf_eval_diffuse(p, n, v, l) + bsdf_eval_specular(p, n, v, l);
}

// Sample the specular lobe: returns l and the weight eval/pdf (F * G2 / G1(v) for VNDF sampling).
// A mirror (roughness ~ 0) returns the exact reflection with weight F. `valid` is false when the
// sampled direction goes below the surface.
vec3 bsdf_sample_specular(BsdfParams p, vec3 n, vec3 v, vec2 u, out vec3 l, out bool valid) {
    float n_v = max(dot(n, v), 1e-4);
    vec3 f0 = bsdf_f0(p);
    if (bsdf_is_mirror(p)) {
        l = reflect(-v, n);
        valid = dot(l, n) > 0.0;
        return fresnel_schlick(f0, n_v);
    }
    float alpha = bsdf_alpha(p);
    mat3 tbn = basis_from_normal(n);
    vec3 v_local = transpose(tbn) * v;
    v_local.z = max(v_local.z, 1e-4);
    vec3 h = tbn * sample_ggx_vndf(normalize(v_local), alpha, u);
    l = reflect(-v, h);
    float n_l = dot(n, l);
    valid = n_l > 0.0;
    if (!valid) return vec3(0.0);
    vec3 f = fresnel_schlick(f0, max(dot(v, h), 0.0));
    return f * (smith_g2(n_v, n_l, alpha) / smith_g1(n_v, alpha));
}

// Pdf of bsdf_sample_specular's direction l (solid angle).
float bsdf_pdf_specular(BsdfParams p, vec3 n, vec3 v, vec3 l) {
    if (bsdf_is_mirror(p)) return 0.0;
    float n_v = max(dot(n, v), 1e-4);
    vec3 h = normalize(v + l);
    float alpha = bsdf_alpha(p);
    return smith_g1(n_v, alpha) * ggx_d(max(dot(n, h), 0.0), alpha) / (4.0 * n_v);
}

// Sample the diffuse lobe (cosine): weight = diffuse albedo.
vec3 bsdf_sample_diffuse(BsdfParams p, vec3 n, vec2 u, out vec3 l) {
    l = basis_from_normal(n) * sample_cosine_hemisphere(u);
    return bsdf_diffuse_albedo(p);
}

// Probability that bsdf_sample picks the specular lobe: its Fresnel-weighted share of the albedo.
float bsdf_specular_probability(BsdfParams m, vec3 n, vec3 v) {
    float ls = luminance(fresnel_schlick(bsdf_f0(m), clamp(dot(n, v), 0.0, 1.0)));
    float ld = luminance(bsdf_diffuse_albedo(m));
    if (ld <= 0.0) return 1.0;
    return clamp(ls / max(ls + ld, 1e-8), 0.05, 0.95);
}

// Solid-angle pdf of bsdf_sample choosing l (its non-delta part).
float bsdf_pdf(BsdfParams m, vec3 n, vec3 v, vec3 l) {
    float n_l = dot(n, l);
    if (n_l <= 0.0) return 0.0;
    float p_spec = bsdf_specular_probability(m, n, v);
    return p_spec * bsdf_pdf_specular(m, n, v, l) + (1.0 - p_spec) * n_l / RAYVR_PI;
}

// The directional albedos of the BSDF's diffuse and specular parts seen from v: what each reflects
// of uniform incident radiance (for demodulating radiance by albedo, and for irradiance probes:
// indirect diffuse = diffuse * irradiance / pi). (Being rewritten with the glTF BSDF: the
// signature stays.)
void bsdf_albedo(BsdfParams b, vec3 n, vec3 v, out vec3 diffuse, out vec3 specular) {
    diffuse = bsdf_diffuse_albedo(b);
    specular = fresnel_schlick(bsdf_f0(b), clamp(dot(n, v), 0.0, 1.0));
}

struct BsdfSample {
    vec3 l;          // sampled direction
    vec3 weight;     // f cos / pdf
    float pdf;       // solid angle; 0 for a delta (mirror) lobe
    bool delta;
};

// One BSDF sample from u in [0,1)^3 (u.xy the direction, u.z the lobe); false when it failed.
bool bsdf_sample(BsdfParams m, vec3 n, vec3 v, vec3 u, out BsdfSample s) {
    float p_spec = bsdf_specular_probability(m, n, v);
    s.delta = false;
    s.pdf = 0.0;
    s.weight = vec3(0.0);
    s.l = n;
    if (u.z < p_spec) {
        bool valid;
        vec3 w = bsdf_sample_specular(m, n, v, u.xy, s.l, valid);
        if (!valid) return false;
        if (bsdf_is_mirror(m)) {
            s.delta = true;
            s.weight = w / p_spec;
            return true;
        }
    } else {
        bsdf_sample_diffuse(m, n, u.xy, s.l);
    }
    float n_l = dot(n, s.l);
    if (n_l <= 0.0) return false;
    s.pdf = p_spec * bsdf_pdf_specular(m, n, v, s.l) + (1.0 - p_spec) * n_l / RAYVR_PI;
    if (!(s.pdf > 0.0)) return false;
    s.weight = bsdf_eval(m, n, v, s.l) / s.pdf;
    return true;
}
