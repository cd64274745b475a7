// Random numbers and importance sampling shared by the ray passes.
// Samplers (Owen-scrambled Sobol, PCG), cosine hemisphere, GGX visible-normal sampling (Heitz 2018),
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

// Random numbers of one path: RAYVR_SAMPLER 1 (default) hash-based Owen-scrambled Sobol (Burley
// 2020, "Practical Hash-based Owen Scrambling"): each call of rng_next/rng_next2/rng_next3 takes
// a new dimension group, a 4D Sobol point whose index is shuffled and whose coordinates are
// Owen-scrambled by nested uniform scrambling with seeds from the pixel, view and pass (per-pixel
// decorrelation) and the group; the sample index runs over the frames (progressive). RAYVR_SAMPLER
// 0: the PCG hash (Jarzynski & Olano 2020) of the earlier versions, for comparisons.
#ifndef RAYVR_SAMPLER
#define RAYVR_SAMPLER 1
#endif

struct Rng {
    uint state;   // PCG: the stream; Sobol: the seed of this path's scrambles
    uint index;   // Sobol: the sample index (frames x samples per frame)
    uint group;   // Sobol: the next dimension group
};

// Sobol direction numbers of dimensions 1-3 (Joe & Kuo's, d = 2, 3, 4); dimension 0 is the van
// der Corput sequence (the bits reversed).
const uint SOBOL_DIRECTIONS[96] = uint[96](
    0x80000000u, 0xc0000000u, 0xa0000000u, 0xf0000000u, 0x88000000u, 0xcc000000u, 0xaa000000u, 0xff000000u,
    0x80800000u, 0xc0c00000u, 0xa0a00000u, 0xf0f00000u, 0x88880000u, 0xcccc0000u, 0xaaaa0000u, 0xffff0000u,
    0x80008000u, 0xc000c000u, 0xa000a000u, 0xf000f000u, 0x88008800u, 0xcc00cc00u, 0xaa00aa00u, 0xff00ff00u,
    0x80808080u, 0xc0c0c0c0u, 0xa0a0a0a0u, 0xf0f0f0f0u, 0x88888888u, 0xccccccccu, 0xaaaaaaaau, 0xffffffffu,
    0x80000000u, 0xc0000000u, 0x60000000u, 0x90000000u, 0xe8000000u, 0x5c000000u, 0x8e000000u, 0xc5000000u,
    0x68800000u, 0x9cc00000u, 0xee600000u, 0x55900000u, 0x80680000u, 0xc09c0000u, 0x60ee0000u, 0x90550000u,
    0xe8808000u, 0x5cc0c000u, 0x8e606000u, 0xc5909000u, 0x6868e800u, 0x9c9c5c00u, 0xeeee8e00u, 0x5555c500u,
    0x8000e880u, 0xc0005cc0u, 0x60008e60u, 0x9000c590u, 0xe8006868u, 0x5c009c9cu, 0x8e00eeeeu, 0xc5005555u,
    0x80000000u, 0xc0000000u, 0x20000000u, 0x50000000u, 0xf8000000u, 0x74000000u, 0xa2000000u, 0x93000000u,
    0xd8800000u, 0x25400000u, 0x59e00000u, 0xe6d00000u, 0x78080000u, 0xb40c0000u, 0x82020000u, 0xc3050000u,
    0x208f8000u, 0x51474000u, 0xfbea2000u, 0x75d93000u, 0xa0858800u, 0x914e5400u, 0xdbe79e00u, 0x25db6d00u,
    0x58800080u, 0xe54000c0u, 0x79e00020u, 0xb6d00050u, 0x800800f8u, 0xc00c0074u, 0x200200a2u, 0x50050093u);

uint sobol(uint index, uint dim) {
    if (dim == 0u) return bitfieldReverse(index);
    uint x = 0u;
    uint base = 32u * (dim - 1u);
    for (; index != 0u; index &= index - 1u) x ^= SOBOL_DIRECTIONS[base + uint(findLSB(index))];
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

#if RAYVR_SAMPLER
// Coordinate `dim` of the current group's point (seed, shuffled index) in [0, 1).
float rng_coordinate(uint index, uint seed, uint dim) {
    return float(nested_uniform_scramble(sobol(index, dim), hash_combine(seed, dim + 1u)) >> 8u) * (1.0 / 16777216.0);
}

// The next dimension group: its seed and its shuffled sample index.
uint rng_group_seed(inout Rng r) { return hash_combine(r.state, pcg_hash(r.group++)); }

float rng_next(inout Rng r) {
    uint seed = rng_group_seed(r);
    uint i = nested_uniform_scramble(r.index, seed);
    return rng_coordinate(i, seed, 0u);
}

vec2 rng_next2(inout Rng r) {
    uint seed = rng_group_seed(r);
    uint i = nested_uniform_scramble(r.index, seed);
    return vec2(rng_coordinate(i, seed, 0u), rng_coordinate(i, seed, 1u));
}

vec3 rng_next3(inout Rng r) {
    uint seed = rng_group_seed(r);
    uint i = nested_uniform_scramble(r.index, seed);
    return vec3(rng_coordinate(i, seed, 0u), rng_coordinate(i, seed, 1u), rng_coordinate(i, seed, 2u));
}
#else
// Uniform float in [0, 1): one PCG step; pcg_hash(state) is the output of the state after it.
float rng_next(inout Rng r) {
    uint word = pcg_hash(r.state);
    r.state = r.state * 747796405u + 2891336453u;
    return float(word >> 8u) * (1.0 / 16777216.0);
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
