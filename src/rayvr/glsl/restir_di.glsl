// ReSTIR DI (Bitterli et al. 2020, "Spatiotemporal reservoir resampling for real-time ray tracing
// with dynamic direct lighting"): what the stages of passes/restir_di share. Include after
// gbuffer.glsl with GBUF_READER.
//
// A reservoir (gpu/records.py RESERVOIR, one rgba32ui texel) holds one light sample by its
// identity (lights.glsl light_id: the light and the point of it), W, its unbiased contribution
// weight in the measure of its light (area for emissive triangles, solid angle for the
// environment, counting for punctual lights), and M, its confidence (the candidates it stands
// for). A pixel's target p_hat is the luminance of the sample's unshadowed contribution there,
// f cos x Le x G in that measure (restir_target), so a sample evaluates alike at every pixel and
// the estimate of a pixel's direct light is f cos Le G x V x W.
//
// Reservoirs combine by generalized RIS (Lin et al. 2022, "Generalized Resampled Importance
// Sampling"): candidate j of the receiving pixel c gets the resampling weight
// m_j(y_j) p_hat_c(y_j) W_j, one is picked by weight, and W = sum / p_hat_c(pick). The MIS weights
// m_j are pairwise (Bitterli 2022, ch. 9; Lin et al. 2022, sec. 7): c against each neighbour i a
// balance heuristic of confidence-weighted targets, each pair with a share of the confidence
// (pair_weight), so that for every sample the weights sum to 1 (unbiased) and, where the targets
// agree, each reservoir counts by its confidence.
#pragma once
#include "shading.glsl"
#include "reprojection.glsl"
#include "octahedral.glsl"
#include "reservoir_records.glsl"   // Reservoir, ReservoirSurface

// ---- reservoirs ----------------------------------------------------------------------------------
Reservoir reservoir_none() { return Reservoir(LIGHT_ID_NONE, 0u, 0.0, 0.0); }

uvec4 reservoir_pack(Reservoir r) {
    return uvec4(r.light, r.point, floatBitsToUint(r.weight), floatBitsToUint(r.confidence));
}

Reservoir reservoir_unpack(uvec4 t) { return Reservoir(t.x, t.y, uintBitsToFloat(t.z), uintBitsToFloat(t.w)); }

uvec2 reservoir_light_id(Reservoir r) { return uvec2(r.light, r.point); }

// ---- the target -----------------------------------------------------------------------------------
// p_hat at vertex s of light sample ls (from light_id_eval: its weight is Le G in its light's
// measure), times `hint` (restir_hint). RESTIR_TARGET 1 (bsdf): the luminance of f cos Le G, with
// the MIS-weighted specular lobes where a reflection pass shares them (`specular_traced`, as
// shade_direct_mis), so the pixel's sum stays right. 0 (cosine): the luminance of Le G cos at the
// geometric normal: no BSDF evaluation (the stages evaluate p_hat at every candidate and
// neighbour), positive wherever f cos Le G is (light_bsdf needs the light above the geometric
// surface), so still unbiased, at more noise where the BSDF is far from Lambert. 2 (auto): the
// bsdf target where the specular lobes carry over RESTIR_GLOSSY_SHARE of the light the surface
// reflects (bsdf_set_view's lobe probabilities), the cosine elsewhere; each pixel's target is a
// function of its own surface, which is all the MIS weights need.
// restir_contribution of a sample from sample_light_id (its weight Le G / pdf) is p_hat / pdf: a
// candidate's resampling weight.
#ifndef RESTIR_TARGET
#define RESTIR_TARGET 1
#endif
const float RESTIR_GLOSSY_SHARE = 0.25;

bool restir_target_uses_bsdf(PathVertex s) {
#if RESTIR_TARGET == 2
    return s.bsdf.lobe_p[BSDF_LOBE_SPECULAR] + s.bsdf.lobe_p[BSDF_LOBE_GLASS] > RESTIR_GLOSSY_SHARE;
#else
    return RESTIR_TARGET == 1;
#endif
}

float restir_contribution(PathVertex s, bool specular_traced, LightSample ls, float hint) {
    if (restir_target_uses_bsdf(s)) return hint * luminance(light_bsdf(s, ls, specular_traced) * ls.weight);
    return ls.valid ? hint * luminance(ls.weight) * max(dot(ls.direction, s.ng), 0.0) : 0.0;
}

// Visibility hints (RESTIR_HINTS): a pixel keeps a bit per light (its identity hashed to one of 32)
// that its last shading ray set where it found that light occluded and cleared where it reached
// it; p_hat of a light whose bit is set is scaled by RESTIR_OCCLUDED_WEIGHT (in (0, 1)), so
// candidates and reuse favour the lights the pixel sees. Any positive factor leaves the estimate
// unbiased (the target only shapes the sampling; every stage's MIS weights use these same targets,
// and a hinted light keeps p_hat > 0 wherever its light reaches). The environment takes no hint
// (one identity for every direction).
uint restir_hint_bit(uvec2 id) { return 1u << ((id.x * 0x9E3779B1u) >> 27u); }

float restir_hint(uint hints, uvec2 id) {
#if RESTIR_HINTS
    if (id.x != LIGHT_ID_NONE && light_id_kind(id) != LIGHT_KIND_ENVIRONMENT && (hints & restir_hint_bit(id)) != 0u)
        return RESTIR_OCCLUDED_WEIGHT;
#endif
    return 1.0;
}

// p_hat, 0 where it is not finite.
float restir_target(PathVertex s, bool specular_traced, LightSample ls, float hint) {
    float t = restir_contribution(s, specular_traced, ls, hint);
    return t > 0.0 && t <= 3.0e38 ? t : 0.0;
}

// p_hat at s, whose pixel has visibility hints `hints`, of the light sample that `id` names.
float restir_target_of(PathVertex s, bool specular_traced, uint hints, uvec2 id) {
    return restir_target(s, specular_traced, light_id_eval(id, s.pos), restir_hint(hints, id));
}

// ---- resampling -----------------------------------------------------------------------------------
// One pick from a stream of weighted candidates (lights.glsl reservoir_take: one random number,
// rescaled after each step), with the pick's target at the receiving pixel.
struct ReservoirStream {
    uvec2 id;
    float target;
    float weight_sum;
    float r;
};

ReservoirStream stream_begin(float r) { return ReservoirStream(uvec2(LIGHT_ID_NONE, 0u), 0.0, 0.0, r); }

void stream_add(inout ReservoirStream s, uvec2 id, float weight, float target) {
    if (!(weight > 0.0) || weight > 3.0e38) return;   // nothing, NaN or Inf
    if (reservoir_take(weight, s.weight_sum, s.r)) {
        s.id = id;
        s.target = target;
    }
}

// The reservoir of the stream's pick: W = weight sum / (normaliser x target), confidence M.
Reservoir stream_reservoir(ReservoirStream s, float confidence, float normaliser) {
    Reservoir r = reservoir_none();
    r.confidence = confidence;
    float w = s.weight_sum / (normaliser * s.target);
    if (s.target > 0.0 && w > 0.0 && w <= 3.0e38) {
        r.light = s.id.x;
        r.point = s.id.y;
        r.weight = w;
    }
    return r;
}

// One pair's balance heuristic of confidence-weighted targets, times the pair's share of the
// confidence (m_self + m_other): the MIS weight, before the stream's normalisation by the total
// confidence, of a reservoir of confidence m_self whose own target at the sample is t_self against
// one of m_other, t_other. Canonical c against k neighbours: a neighbour's sample y_i gets
// pair_weight(M_i, p_i(y_i), M_c / k, p_c(y_i)); c's sample y_c the sum over the neighbours of
// pair_weight(M_c / k, p_c(y_c), M_i, p_i(y_c)); the shares add up to M_c + sum M_i.
float pair_weight(float m_self, float t_self, float m_other, float t_other) {
    float a = m_self * t_self, b = m_other * t_other;
    return a > 0.0 ? (m_self + m_other) * (a / (a + b)) : 0.0;
}

// ---- surfaces -------------------------------------------------------------------------------------
// A neighbour's surface counts as this pixel's when its effect word is the same, its normal is
// within ~25 degrees and its linear depth within this fraction of this pixel's.
const float RESTIR_NEIGHBOUR_DEPTH = 0.1;

bool restir_neighbour_matches(float depth, vec3 n, uint word, float q_depth, vec3 q_n, uint q_word) {
    return q_depth > 0.0 && reprojection_matches(q_depth, q_n, q_word, depth, n, word, RESTIR_NEIGHBOUR_DEPTH * depth);
}

uvec4 reservoir_surface_pack(float depth, vec3 n, uint word, vec3 v) {
    return uvec4(floatBitsToUint(depth), oct_pack_snorm16(n), word, oct_pack_snorm16(v));
}

ReservoirSurface reservoir_surface_unpack(uvec4 t) { return ReservoirSurface(uintBitsToFloat(t.x), t.y, t.z, t.w); }
