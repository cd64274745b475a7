// Lobe BSDF_LOBE_DIFFUSE (bsdf_lobes.glsl): the dielectric's Lambert base under its specular layer,
// weighted by what the layer leaves: (1 - E(mu_v)) (1 - E(mu_l)) / (1 - E_avg) base / pi (E: the
// layer's directional albedo; Kulla & Conty 2017's albedo scaling, which makes glTF's "(1 - F)
// diffuse" conserve energy exactly; max over RGB as KHR_materials_specular prescribes for a
// coloured F0). Sampled by the cosine.
#pragma once
#include "bsdf_terms.glsl"

bool bsdf_diffuse_sample(vec3 n, vec2 u, inout vec3 l) {
    l = basis_from_normal(n) * sample_cosine_hemisphere(u);
    return true;
}

// f |n.l| for l above the surface.
vec3 bsdf_diffuse_eval_above(BsdfParams b, vec3 n, vec3 v, vec3 l) {
    float nv = dot(n, v), nl = dot(n, l);
    vec3 w = bsdf_weights(b);
    if (nv <= 0.0 || nl <= 0.0 || w.x <= 0.0) return vec3(0.0);
    float el = b.f90 > 0.0 ? bsdf_dielectric_layer(b, bsdf_table_ab(nl, b.roughness)) : 0.0;
    return w.x * b.base_color * ((1.0 - b.layer_v) * (1.0 - el) / max(1.0 - b.layer_avg, 1e-4) / RAYVR_PI * nl);
}

void bsdf_diffuse_add_albedo(BsdfParams b, inout vec3 albedo) {
    albedo += bsdf_weights(b).x * b.base_color * (1.0 - max3(bsdf_layer_albedo(b.f0, b.f90, b.ab_v)));
}
