// Random numbers and importance sampling shared by the ray passes.
// Samplers (Owen-scrambled Sobol, PCG), cosine hemisphere, GGX visible-normal sampling (Heitz 2018),
// an orthonormal basis (Duff et al. 2017) and the MIS power heuristic.
#pragma once
#include "rng_salts.glsl"   // RNG_SALT_<NAME>: the salts of rng_init's streams

#ifndef RAYVR_PI
#define RAYVR_PI 3.14159265358979323846
#endif

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Random numbers of one path: RAYVR_SAMPLER 1 (default) hash-based Owen-scrambled Sobol (Burley
// 2020, "Practical Hash-based Owen Scrambling"): each call of rng_next/rng_next2/rng_next3 takes
// a new dimension group, whose sample index is shuffled and whose coordinates are Owen-scrambled
// (nested uniform scrambling seeded by the pixel, view, pass and group: per-pixel
// decorrelation); the sample index runs over the frames (progressive). A group's pair is the
// first two Sobol dimensions, a (0,2)-sequence, computed without a table (a table's lookups at
// shuffled, per-lane indices serialise in the constant cache: measured 4x slower on a GPU);
// rng_next3's third coordinate is a van der Corput point under its own shuffle (Burley's
// padding). RAYVR_SAMPLER 0: the PCG hash (Jarzynski & Olano 2020), for comparisons.
#ifndef RAYVR_SAMPLER
#define RAYVR_SAMPLER 1
#endif

struct Rng {
    uint state;   // PCG: the stream; Sobol: the seed of this path's scrambles
    uint index;   // Sobol: the sample index (frames x samples per frame)
    uint group;   // Sobol: the next dimension group
};

// Sobol dimension 1 (dimension 0 is bitfieldReverse(index)): its direction numbers are the rows
// of Pascal's triangle mod 2, v_{k+1} = v_k ^ (v_k >> 1) from v_0 = 2^31.
uint sobol_dimension1(uint index) {
    uint x = 0u;
    for (uint v = 0x80000000u; index != 0u; index >>= 1u, v ^= v >> 1u)
        if ((index & 1u) != 0u) x ^= v;
    return x;
}

// Laine & Karras' hash-based Owen scrambling, as Burley's nested uniform scramble.
uint laine_karras_permutation(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

uint hash_combine(uint seed, uint v) { return seed ^ (v + (seed << 6) + (seed >> 2)); }

// Frames in one Sobol sequence: a render started 2^16 frames away (an independent stream, as the
// error study's references are) gets other scrambles.
#define RAYVR_SOBOL_FRAMES_LOG2 16u

// A path's generator: pixel, view, frame, salt (a pass's own), sample `k` of the frame's
// `samples` (its index in the sequence is frame * samples + k).
Rng rng_init_sample(uvec2 pixel, uint view, uint frame, uint salt, uint k, uint samples) {
    Rng r;
#if RAYVR_SAMPLER
    r.state = pcg_hash(pixel.x + pcg_hash(pixel.y + pcg_hash(view + pcg_hash(salt
              + pcg_hash(frame >> RAYVR_SOBOL_FRAMES_LOG2)))));
    r.index = (frame & ((1u << RAYVR_SOBOL_FRAMES_LOG2) - 1u)) * max(samples, 1u) + k;
#else
    r.state = pcg_hash(pixel.x + pcg_hash(pixel.y + pcg_hash(view + pcg_hash(frame
              + pcg_hash(salt + 0x9E3779B9u * k)))));
    r.index = 0u;
#endif
    r.group = 0u;
    return r;
}

Rng rng_init(uvec2 pixel, uint view, uint frame, uint salt) { return rng_init_sample(pixel, view, frame, salt, 0u, 1u); }

// The one word of a generator that its draws change (Sobol: the dimension group; PCG: the
// state): with the generator it started as, all that a path must keep to go on drawing.
uint rng_word(Rng r) {
#if RAYVR_SAMPLER
    return r.group;
#else
    return r.state;
#endif
}

Rng rng_resume(Rng start, uint word) {
#if RAYVR_SAMPLER
    start.group = word;
#else
    start.state = word;
#endif
    return start;
}

// A uniform float in [0, 1) from the top 24 bits.
float rng_unit(uint bits) { return float(bits >> 8u) * (1.0 / 16777216.0); }

// Point `index` of a one-dimensional Owen-scrambled Sobol (van der Corput) sequence whose index
// shuffle and scramble are seeded by `seed`: consecutive indices are stratified, two seeds'
// sequences independent. rng_next's dimension, and alphaMode BLEND's decisions (scene.glsl).
float sobol_1d(uint index, uint seed) {
    uint i = nested_uniform_scramble(index, seed);
    return rng_unit(nested_uniform_scramble(bitfieldReverse(i), hash_combine(seed, 1u)));
}

#if RAYVR_SAMPLER
// The next dimension group's seed.
uint rng_group_seed(inout Rng r) { return hash_combine(r.state, pcg_hash(r.group++)); }

float rng_next(inout Rng r) { return sobol_1d(r.index, rng_group_seed(r)); }

vec2 rng_next2(inout Rng r) {
    uint seed = rng_group_seed(r);
    uint i = nested_uniform_scramble(r.index, seed);
    return vec2(rng_unit(nested_uniform_scramble(bitfieldReverse(i), hash_combine(seed, 1u))),
                rng_unit(nested_uniform_scramble(sobol_dimension1(i), hash_combine(seed, 2u))));
}

vec3 rng_next3(inout Rng r) {
    vec2 xy = rng_next2(r);
    return vec3(xy, rng_next(r));
}
#else
// Uniform float in [0, 1): one PCG step; pcg_hash(state) is the output of the state after it.
float rng_next(inout Rng r) {
    uint word = pcg_hash(r.state);
    r.state = r.state * 747796405u + 2891336453u;
    return rng_unit(word);
}

vec2 rng_next2(inout Rng r) { return vec2(rng_next(r), rng_next(r)); }
vec3 rng_next3(inout Rng r) { return vec3(rng_next(r), rng_next(r), rng_next(r)); }
#endif

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
