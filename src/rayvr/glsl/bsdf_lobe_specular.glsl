// Lobe BSDF_LOBE_SPECULAR (bsdf_lobes.glsl): the GGX reflection of the dielectric's specular layer
// (Schlick Fresnel f0, f90) and of the metal (Schlick Fresnel on the base colour, f90 = 1), each
// compensated for single scattering by 1 + f0 (1 / E_ss - 1) (Turquin 2019). Its Fresnel factor
// rides on the GGX reflection term that bsdf.glsl shares among the reflecting lobes.
#pragma once
#include "bsdf_terms.glsl"

// A reflection about a visible normal from u (about n when delta).
bool bsdf_specular_sample(BsdfParams b, vec3 n, vec3 v, vec2 u, inout vec3 l, inout bool delta) {
    delta = bsdf_is_delta(b);
    l = reflect(-v, delta ? n : bsdf_sample_vndf(b, n, v, u));
    return dot(n, l) > 0.0;
}

void bsdf_specular_add_fresnel(BsdfParams b, float vh, inout vec3 fresnel) {
    vec3 w = bsdf_weights(b);
    fresnel += w.x * fresnel_schlick(b.f0, b.f90, vh) * (1.0 + b.f0 * (1.0 / b.ess_v - 1.0))
             + w.z * fresnel_schlick(b.base_color, vh) * (1.0 + b.base_color * (1.0 / b.ess_v - 1.0));
}

void bsdf_specular_add_albedo(BsdfParams b, inout vec3 albedo) {
    vec3 w = bsdf_weights(b);
    albedo += w.x * bsdf_layer_albedo(b.f0, b.f90, b.ab_v) + w.z * bsdf_layer_albedo(b.base_color, 1.0, b.ab_v);
}
