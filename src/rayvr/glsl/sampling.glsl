// Random numbers and importance sampling shared by the ray passes.
// PCG hash RNG (Jarzynski & Olano 2020), cosine hemisphere, GGX visible-normal sampling (Heitz 2018),
// an orthonormal basis (Duff et al. 2017) and the MIS power heuristic.
#pragma once

#ifndef RAYVR_PI
#define RAYVR_PI 3.14159265358979323846
#endif

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng { uint state; };

// A stream per (pixel, view, frame, salt): different passes use different salts.
Rng rng_init(uvec2 pixel, uint view, uint frame, uint salt) {
    uint s = pcg_hash(pixel.x + pcg_hash(pixel.y + pcg_hash(view + pcg_hash(frame + pcg_hash(salt)))));
    return Rng(s);
}

// Uniform float in [0, 1): one PCG step; pcg_hash(state) is the output of the state after it.
float rng_next(inout Rng r) {
    uint word = pcg_hash(r.state);
    r.state = r.state * 747796405u + 2891336453u;
    return float(word >> 8u) * (1.0 / 16777216.0);
}

vec2 rng_next2(inout Rng r) { return vec2(rng_next(r), rng_next(r)); }
vec3 rng_next3(inout Rng r) { return vec3(rng_next(r), rng_next(r), rng_next(r)); }

// Orthonormal basis around unit n: columns t, b, n (branchless, Duff et al. 2017).
mat3 basis_from_normal(vec3 n) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
    return mat3(t, bt, n);
}

// Cosine-weighted direction about +Z; pdf = cos(theta) / pi.
vec3 sample_cosine_hemisphere(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * RAYVR_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// GGX visible normal about +Z for view direction `ve` (local, ve.z > 0), roughness alpha
// (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").
vec3 sample_ggx_vndf(vec3 ve, float alpha, vec2 u) {
    vec3 vh = normalize(vec3(alpha * ve.x, alpha * ve.y, max(ve.z, 1e-6)));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 1e-12 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * RAYVR_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(nh.z, 1e-6)));
}

float power_heuristic(float pdf_a, float pdf_b) {
    float a = pdf_a * pdf_a;
    float b = pdf_b * pdf_b;
    return a + b > 0.0 ? a / (a + b) : 0.0;
}
