// What the BSDF's lobes (bsdf_lobes.glsl) share: the parameters of a material's BSDF, the energy
// tables (rayvr/materials/bsdf_tables.py), the microfacet terms (GGX D, Smith, Schlick and exact
// dielectric Fresnel) and the GGX reflection's visible-normal sampling and pdf. Included by the
// lobe table after BSDF_LOBE_COUNT; shaders include bsdf.glsl.
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
    // hemispherical average, the lobes' sampling probabilities (by BSDF_LOBE_* index)
    float nv;
    vec2 ab_v;
    float ess_v;
    float glass_comp_v;
    float layer_v;
    float layer_avg;
    BsdfLobeFloats lobe_p;
};

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

// ---- the lobes' mix -----------------------------------------------------------------------------
// (w_dielectric, w_glass, w_metal): the mix of the three BSDFs.
vec3 bsdf_weights(BsdfParams b) {
    return vec3((1.0 - b.metallic) * (1.0 - b.transmission), (1.0 - b.metallic) * b.transmission, b.metallic);
}

// The dielectric's specular layer albedo at mu (max over RGB) and its average.
float bsdf_dielectric_layer(BsdfParams b, vec2 ab) { return max3(bsdf_layer_albedo(b.f0, b.f90, ab)); }

// ---- the GGX reflection the specular lobes share ------------------------------------------------
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

