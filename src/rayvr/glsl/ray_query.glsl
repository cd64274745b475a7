// Ray queries against the two-level BVH of rayvr.scene.GpuScene (see rayvr/scene/bvh.py, bvh_wide.py).
//
//   bool trace_closest(vec3 o, vec3 d, float tmax, out Hit hit)   closest hit in (0, tmax)
//   bool trace_occluded(vec3 o, vec3 d, float tmax)               any hit in (0, tmax), exits early
//   float trace_transmittance(vec3 o, vec3 d, float tmax)         the fraction of light from tmax
//       that reaches o: 0 behind an opaque (or MASK-passing) hit, found or not after BLEND ones
//       (it ends the ray at once), else the product of (1 - alpha) over the BLEND surfaces in
//       (0, tmax), each counted once (a shadow ray's expected visibility, where trace_occluded
//       decides each BLEND surface by a coin). No random decision unless RQ_BLEND_ROULETTE > 0:
//       then a product below it goes on by Russian roulette (rq_blend_dims), equal in expectation
//   vec3 offset_ray_origin(vec3 p, vec3 ng)                       self-intersection-free origin
//   Each query also takes a `uint skip` before its last argument (trace_closest(o, d, tmax,
//   skip, hit)): an instance the ray cannot meet, which the traversal does not enter. A ray that
//   leaves a surface on its geometric normal's side passes SurfacePoint.exit_instance (set where
//   the whole mesh lies behind the hit triangle, rayvr.scene.convex_faces): a bounce or shadow
//   ray off a convex mesh then skips that mesh's BLAS. SCENE_NO_INSTANCE: skip nothing.
//
// Render space; d need not be normalised (t is in units of d) but |d| should be ~1 and
// tmax <= 1e29. `Hit` is declared in scene.glsl. Both faces are hit; alpha-masked materials
// are tested in the any-hit step (SCENE_HAS_ALPHA_MASK), and so are alphaMode BLEND ones
// (SCENE_HAS_ALPHA_BLEND): stochastic transparency, a surface of alpha a is hit with probability
// a (scene.glsl material_blend_passes), by both queries. A kernel seeds the decisions of its
// invocation's rays with rq_blend_begin(Rng) (its path's generator: pixel, view, frame, sample)
// before its first query; each query after it is a new ray of that path. Without BLEND in the
// scene rq_blend_begin compiles to nothing.
//
// Layout (the interface of every BVH builder; RQ_BVH_WIDTH and RQ_BVH_QUANTIZED, from
// GpuScene.defines(), say which one GpuScene uploaded, for both levels). Children's boxes live in
// the parent, links as uint bits.
//   "bvh2", RQ_BVH_WIDTH 2 (rayvr/scene/bvh.py): 64 B = vec4(min0, link0) vec4(max0, count0)
//     vec4(min1, link1) vec4(max1, count1); count 0: link is a node index, count 1..8: a leaf of
//     that many BVH slots from link (< 2**28). 4 vec4 loads, two rq_box tests per node.
//   "bvh4", RQ_BVH_WIDTH 4 (rayvr/scene/bvh_wide.py, collapsed from the BVH2): 112 B = the 4
//     children's min.x, max.x, min.y, max.y, min.z, max.z (one vec4 each) and uvec4 of their work
//     items (see rq_item); 7 vec4 loads, one rq_box4 per node; an empty child's box is at 1e30.
//   "bvh4q", RQ_BVH_WIDTH 4 + RQ_BVH_QUANTIZED 1 (the same collapse, boxes on an 8-bit grid per
//     node): 64 B = vec4(origin, exponent bytes) uvec4(lo.x, hi.x, lo.y, hi.y) uvec4(lo.z, hi.z, -, -)
//     uvec4 items, each lo/hi word one byte per child; child plane = origin + float(q) * 2^e, a
//     box that holds the exact one. 4 vec4 loads, one rq_box4q per node; an empty child has item 0.
//   "bvh8", RQ_BVH_WIDTH 8 (rayvr/scene/bvh8.py, Ylitie et al. 2017's compressed wide BVH): 80 B =
//     vec4(origin, exponent bytes | imask << 24) uvec4(child base, triangle base, meta 0..3, meta 4..7)
//     and per axis uvec4(lo 0..3, lo 4..7, hi 0..3, hi 4..7) bytes; children in direction slots
//     (slot r ^ octant is a ray's r-th), internal ones consecutive from the child base, a leaf's
//     triangles at triangle base + (meta & 31), meta >> 5 of them. 5 vec4 loads, two rq_qbox4 per
//     node; its TLAS's triangle base indexes a uint table of instance ids in the TLAS buffer.
// A TLAS leaf (count 1) links an instance (bvh8: through the table). Triangle slots are three vec4 (object-space vertices;
// w of the first: the mesh-local triangle index, of the second: its material's alpha mode as uint bits).
//
// Traversal: ONE loop over both levels (a TLAS leaf moves the ray into the instance's object
// space and the loop continues in its BLAS; popping back to the entry depth moves it back), near
// child first, the other hit children on a per-invocation stack (BVH4: sorted by entry distance
// with a 5-comparator network and pushed far to near). One node fetch or one leaf per iteration
// from one call site keeps a warp's lanes in step (several times faster than nested TLAS/BLAS
// loops with the BLAS loop inlined at three call sites). The loop body is a step function over
// per-invocation globals (rq_begin / rq_step), so a kernel may also interleave steps with its
// own work; compilers schedule this form better than the same body in a loop over locals (a
// state struct passed inout is copied, and was far slower). bvh4q decodes a node's 4 boxes
// (one fma per plane whose only rounding is the add's: the float box bvh_wide.decode computes,
// which holds the exact one) and slab-tests them with bvh4's float operations, near and far
// planes picked by the ray's signs: it enters every box bvh4 enters, and a few more. bvh8 takes
// each plane's slab distance in one fma from per-node constants, widened by a bound of its
// rounding (RQ_BVH8_FMA_BOX; 0: bvh4q's decode). Its stack holds groups, not nodes (after Ylitie et al.): a node group is
// a node's hit internal children (child base, hit bits by visiting rank, imask), a leaf group a
// node's hit leaves (first slot, a bit per triangle slot; in the TLAS a bit per instance); a step
// visits the group's nearest child node and keeps the rest as the current group, or tests a leaf
// group's triangles, or enters one instance; a node's group is pushed only when a child's
// replaces it, so a node costs at most one push.
//
// #defines: RQ_TRIANGLE 1 (default) Moeller-Trumbore with edges widened by RQ_EDGE_EPS
// (barycentric) so shared edges have no cracks; 0 the watertight test of Woop, Benthin & Wald 2013
// (exact at edges, ~1.5x slower primary rays); 2 the same without its fp64 edge fallback.
// RQ_STACK_SIZE (64; bvh8: half as many uvec2 groups, the same bytes). RQ_BVH_WIDTH 2, 4 or 8,
// RQ_BVH_QUANTIZED 0 or 1 (the uploaded layout).
// RQ_BVH8_FMA_BOX (1): bvh8's box test as one fma per plane, widened by a bound of its rounding (0:
// the decode and slab test of bvh4q, entering exactly the boxes of the decoded planes).
// RQ_BLEND_ROULETTE (0.0): trace_transmittance's roulette threshold (0: the exact product; 1: a
// coin per BLEND surface, as trace_occluded; between: exact while the product stays above it).
// RQ_STATS 1: count per invocation rq_stat_nodes (internal nodes visited, of RQ_BVH_WIDTH),
// rq_stat_triangles (triangle tests) and rq_stat_instances (BLAS entries) for the kernel to store.
// RQ_CONVEX_SKIP 1 (GpuScene.defines(): the scene has such triangles): the traversal honours
// `skip`; 0 compiles it out.
// RQ_COUNT_RAYS 1: rq_rays counts the queries the invocation began (glsl/ray_counters.glsl sums them per view).
#pragma once
#include "scene.glsl"

#ifndef RQ_STACK_SIZE
#define RQ_STACK_SIZE 64
#endif
#ifndef RQ_TRIANGLE
#define RQ_TRIANGLE 1        // 1: Moeller-Trumbore with widened edges, 0: watertight (Woop et al. 2013), 2: 0 without its fp64 edge fallback
#endif
#ifndef RQ_EDGE_EPS
#define RQ_EDGE_EPS 1e-7     // RQ_TRIANGLE 1: barycentric tolerance at the edges
#endif
#ifndef RQ_STATS
#define RQ_STATS 0
#endif
#ifndef RQ_BVH8_FMA_BOX
#define RQ_BVH8_FMA_BOX 1       // bvh8: one fma per box plane, widened to stay conservative (0: bvh4q's exact decode)
#endif
#ifndef RQ_BLEND_ROULETTE
#define RQ_BLEND_ROULETTE 0.0   // trace_transmittance: below this product of (1 - alpha), Russian roulette (0: exact)
#endif
#ifndef RQ_CONVEX_SKIP
#define RQ_CONVEX_SKIP 0
#endif
#ifndef RQ_BVH_WIDTH
#define RQ_BVH_WIDTH 4       // the node layout GpuScene uploaded: 2 (BVH2), 4 (BVH4) or 8 (BVH8); GpuScene.defines() sets it
#endif
#ifndef RQ_BVH_QUANTIZED
#define RQ_BVH_QUANTIZED 0   // RQ_BVH_WIDTH 4: 64 B nodes of 8-bit child boxes (1) or 112 B float boxes (0)
#endif
#if RQ_BVH_WIDTH == 8
#define RQ_NODE_VEC4S 5      // vec4s per node
#elif RQ_BVH_WIDTH == 4 && !RQ_BVH_QUANTIZED
#define RQ_NODE_VEC4S 7
#else
#define RQ_NODE_VEC4S 4
#endif

layout(std430, binding = RAYVR_BLAS_NODE_SSBO) readonly buffer RqBlasNodes { vec4 rq_blas_nodes[]; };
layout(std430, binding = RAYVR_TLAS_NODE_SSBO) readonly buffer RqTlasNodes { vec4 rq_tlas_nodes[]; };
// three vec4 per BVH slot: vertices in object space; w of the first: mesh-local triangle index, of the second: alpha mode
layout(std430, binding = RAYVR_TRIANGLE_SSBO) readonly buffer RqTriangles { vec4 rq_triangles[]; };

#ifndef SCENE_SCALE
#define SCENE_SCALE 1.0
#endif

// Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray Tracing Gems
// ch. 6): move p along the geometric normal by a few ULPs of its own magnitude (an integer step
// on the float bits), or by a fixed tiny distance near the origin where ULPs vanish. The paper's
// constants are for scenes of about a metre; here they scale with the scene's extent
// (SCENE_SCALE, from GpuScene.defines()), so a millimetre scene is not offset by 3% of its size.
vec3 offset_ray_origin(vec3 p, vec3 ng) {
    const float near_origin = SCENE_SCALE / 32.0;
    const float float_step = SCENE_SCALE / 65536.0;
    const float int_step = 256.0;
    ivec3 di = ivec3(int_step * ng);
    vec3 pi = intBitsToFloat(floatBitsToInt(p) + ivec3(p.x < 0.0 ? -di.x : di.x,
                                                        p.y < 0.0 ? -di.y : di.y,
                                                        p.z < 0.0 ? -di.z : di.z));
    return vec3(abs(p.x) < near_origin ? p.x + float_step * ng.x : pi.x,
                abs(p.y) < near_origin ? p.y + float_step * ng.y : pi.y,
                abs(p.z) < near_origin ? p.z + float_step * ng.z : pi.z);
}

vec3 rq_safe_inverse(vec3 d) {
    const float big = 1e20;
    return vec3(abs(d.x) > 1e-20 ? 1.0 / d.x : (d.x < 0.0 ? -big : big),
                abs(d.y) > 1e-20 ? 1.0 / d.y : (d.y < 0.0 ? -big : big),
                abs(d.z) > 1e-20 ? 1.0 / d.z : (d.z < 0.0 ? -big : big));
}

// Slab test of box [lo, hi] (origin * inv = oi): entry distance, or a negative value on a miss.
// The exit is widened by 2 ulp so that rounding never loses a box a watertight ray touches.
float rq_box(vec3 lo, vec3 hi, vec3 inv, vec3 oi, float tmax) {
    vec3 t0 = lo * inv - oi, t1 = hi * inv - oi;
    vec3 tn = min(t0, t1), tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float leave = min(min(tf.x, tf.y), min(tf.z, tmax)) * 1.00000024;
    return enter <= leave ? enter : -1.0;
}

#if RQ_BVH_WIDTH >= 4
#define RQ_MISS 3.0e38   // rq_box4's distance of a box the ray misses

// rq_box of the 4 child boxes of a BVH4 node at once (struct of arrays: lox holds min.x of
// children 0..3, ...): entry distances, RQ_MISS where missed. The same float operations per
// box as rq_box, so both widths enter exactly the same boxes.
vec4 rq_box4(vec4 lox, vec4 hix, vec4 loy, vec4 hiy, vec4 loz, vec4 hiz, vec3 inv, vec3 oi, float tmax) {
    vec4 x0 = lox * inv.x - oi.x, x1 = hix * inv.x - oi.x;
    vec4 y0 = loy * inv.y - oi.y, y1 = hiy * inv.y - oi.y;
    vec4 z0 = loz * inv.z - oi.z, z1 = hiz * inv.z - oi.z;
    vec4 enter = max(max(min(x0, x1), min(y0, y1)), max(min(z0, z1), vec4(0.0)));
    vec4 leave = min(min(max(x0, x1), max(y0, y1)), min(max(z0, z1), vec4(tmax))) * 1.00000024;
    return mix(vec4(RQ_MISS), enter, lessThanEqual(enter, leave));
}

#if RQ_BVH_QUANTIZED
// The 4 bytes of a word, one per child, as floats: each byte as the low mantissa bits of 2^23
// (one OR), minus 2^23, which is exact and avoids an int-to-float conversion (a quarter-rate op).
vec4 rq_bytes(uint w) {
    uvec4 b = (uvec4(w) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu;
    return uintBitsToFloat(b | 0x4B000000u) - 8388608.0;
}

// The grid steps 2^e of a quantised node from its exponent bytes (bits 0..23 of `e`).
vec3 rq_grid_scale(uint e) { return uintBitsToFloat((uvec3(e, e >> 8, e >> 16) & 0xFFu) << 23); }

// rq_box4 of 4 quantised child boxes: lo and hi hold their lower and upper planes' bytes per axis.
// Each plane decodes as origin + q * scale (exact product: one rounding, fused or not), then the
// same float operations as rq_box4; taking the near plane from lo or hi by the ray's sign gives
// rq_box4's min/max for every box that is not inverted.
vec4 rq_qbox4(vec3 origin, vec3 scale, uvec3 lo, uvec3 hi, vec3 inv, vec3 oi, float tmax) {
    bvec3 neg = lessThan(inv, vec3(0.0));
    vec4 nx = (origin.x + rq_bytes(neg.x ? hi.x : lo.x) * scale.x) * inv.x - oi.x;
    vec4 fx = (origin.x + rq_bytes(neg.x ? lo.x : hi.x) * scale.x) * inv.x - oi.x;
    vec4 ny = (origin.y + rq_bytes(neg.y ? hi.y : lo.y) * scale.y) * inv.y - oi.y;
    vec4 fy = (origin.y + rq_bytes(neg.y ? lo.y : hi.y) * scale.y) * inv.y - oi.y;
    vec4 nz = (origin.z + rq_bytes(neg.z ? hi.z : lo.z) * scale.z) * inv.z - oi.z;
    vec4 fz = (origin.z + rq_bytes(neg.z ? lo.z : hi.z) * scale.z) * inv.z - oi.z;
    vec4 enter = max(max(nx, ny), max(nz, vec4(0.0)));
    vec4 leave = min(min(fx, fy), min(fz, vec4(tmax))) * 1.00000024;
    return mix(vec4(RQ_MISS), enter, lessThanEqual(enter, leave));
}

#if RQ_BVH_WIDTH == 8 && RQ_BVH8_FMA_BOX
// rq_qbox4 with one fma per plane (after Ylitie et al.): t = q * (scale * inv) + (origin - o) * inv,
// the near planes' constant lowered and the far planes' raised by a bound of that form's rounding
// against the decoded box's exact slab distances (each of the three roundings of t is within
// 2^-24 of |q * scale * inv| + |(origin - o) * inv|, and the real plane origin + q * scale lies
// within 2^-24 |plane| of the float one that holds the box; 2^-21 covers all with room), so it
// enters every box rq_qbox4 enters. s, cn, cf: the node's per-axis scale * inv and near / far
// constants (rq_qbox_consts).
void rq_qbox_consts(vec3 origin, vec3 scale, vec3 inv, vec3 o, out vec3 s, out vec3 cn, out vec3 cf) {
    s = scale * inv;
    vec3 c = (origin - o) * inv;
    vec3 err = 4.76837158e-7 * (256.0 * abs(s) + abs(c) + abs(origin * inv));   // 2^-21 x
    cn = c - err;
    cf = c + err;
}

vec4 rq_qbox4_fma(vec3 s, vec3 cn, vec3 cf, uvec3 lo, uvec3 hi, bvec3 neg, float tmax) {
    vec4 nx = rq_bytes(neg.x ? hi.x : lo.x) * s.x + cn.x, fx = rq_bytes(neg.x ? lo.x : hi.x) * s.x + cf.x;
    vec4 ny = rq_bytes(neg.y ? hi.y : lo.y) * s.y + cn.y, fy = rq_bytes(neg.y ? lo.y : hi.y) * s.y + cf.y;
    vec4 nz = rq_bytes(neg.z ? hi.z : lo.z) * s.z + cn.z, fz = rq_bytes(neg.z ? lo.z : hi.z) * s.z + cf.z;
    vec4 enter = max(max(nx, ny), max(nz, vec4(0.0)));
    vec4 leave = min(min(fx, fy), min(fz, vec4(tmax))) * 1.00000024;
    return mix(vec4(RQ_MISS), enter, lessThanEqual(enter, leave));
}
#endif

#if RQ_BVH_WIDTH == 4
// rq_box4 of a bvh4q node (header: origin, exponent bytes; q: lo.x, hi.x, lo.y, hi.y bytes; qz: lo.z,
// hi.z). Empty slots (item 0) are missed.
vec4 rq_box4q(vec4 header, uvec4 q, uvec2 qz, uvec4 items, vec3 inv, vec3 oi, float tmax) {
    vec4 t = rq_qbox4(header.xyz, rq_grid_scale(floatBitsToUint(header.w)), uvec3(q.x, q.z, qz.x),
                      uvec3(q.y, q.w, qz.y), inv, oi, tmax);
    // an inverted box fails the slab test only by more than the 2 ulp widening: item 0 never passes
    return mix(t, vec4(RQ_MISS), equal(items, uvec4(0u)));
}
#endif
#endif

#if RQ_BVH_WIDTH == 4
// One comparator of the sorting network: (ta, ca) gets the nearer of the two children.
#define RQ_ORDER(ta, ca, tb, cb) if (tb < ta) { float t_ = ta; ta = tb; tb = t_; uint c_ = ca; ca = cb; cb = c_; }
#endif
#endif

// The per-ray constants of the watertight test in one instance's object space. Coordinates are
// permuted so that z is the dominant axis of d (swizzles, no dynamic indexing).
struct RqRay {
    vec3 o;
    vec3 d;
    vec3 inv;
    vec3 oi;
    int perm;    // which of the six axis permutations (kx, ky, kz)
    vec3 shear;  // Sx, Sy, Sz
};

vec3 rq_permute(vec3 v, int perm) {
    switch (perm) {
        case 0: return v.yzx;   // kz = x
        case 1: return v.zyx;
        case 2: return v.zxy;   // kz = y
        case 3: return v.xzy;
        case 4: return v.xyz;   // kz = z
        default: return v.yxz;
    }
}

RqRay rq_make_ray(vec3 o, vec3 d) {
    RqRay r;
    r.o = o;
    r.d = d;
    r.inv = rq_safe_inverse(d);
    r.oi = o * r.inv;
#if RQ_TRIANGLE != 1
    vec3 ad = abs(d);
    int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    float dz = kz == 0 ? d.x : (kz == 1 ? d.y : d.z);
    r.perm = 2 * kz + (dz < 0.0 ? 1 : 0);   // swapping kx, ky keeps the projected winding
    vec3 dp = rq_permute(d, r.perm);
    r.shear = vec3(dp.x / dp.z, dp.y / dp.z, 1.0 / dp.z);
#endif
    return r;
}

#if RQ_TRIANGLE != 1
// Watertight ray/triangle test: on a hit nearer than tmax, returns true with t and barycentrics.
bool rq_triangle(RqRay r, vec3 v0, vec3 v1, vec3 v2, float tmax, out float t, out vec2 bary) {
    vec3 a = rq_permute(v0 - r.o, r.perm), b = rq_permute(v1 - r.o, r.perm), c = rq_permute(v2 - r.o, r.perm);
    float ax = a.x - r.shear.x * a.z, ay = a.y - r.shear.y * a.z;
    float bx = b.x - r.shear.x * b.z, by = b.y - r.shear.y * b.z;
    float cx = c.x - r.shear.x * c.z, cy = c.y - r.shear.y * c.z;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
#if RQ_TRIANGLE == 0
    if (u == 0.0 || v == 0.0 || w == 0.0) {   // on an edge in float: decide in double
        u = float(double(cx) * double(by) - double(cy) * double(bx));
        v = float(double(ax) * double(cy) - double(ay) * double(cx));
        w = float(double(bx) * double(ay) - double(by) * double(ax));
    }
#endif
    t = 0.0;
    bary = vec2(0.0);
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    float det = u + v + w;
    if (det == 0.0) return false;
    float tt = r.shear.z * (u * a.z + v * b.z + w * c.z);
    float sgn = det < 0.0 ? -1.0 : 1.0;
    if (tt * sgn <= 0.0 || tt * sgn > tmax * abs(det)) return false;
    float rcp = 1.0 / det;
    t = tt * rcp;
    bary = vec2(v, w) * rcp;
    return true;
}

#else
// Moeller-Trumbore ray/triangle test, same contract as the watertight one. The edges are
// widened by RQ_EDGE_EPS in barycentric units, so a ray through a shared edge hits at least one of
// its triangles despite rounding (no cracks; an edge ray may report either neighbour).
bool rq_triangle(RqRay r, vec3 v0, vec3 v1, vec3 v2, float tmax, out float t, out vec2 bary) {
    vec3 e1 = v1 - v0, e2 = v2 - v0;
    vec3 p = cross(r.d, e2);
    float rcp = 1.0 / dot(e1, p);   // +-inf for a ray in the triangle's plane: u, v become NaN or inf
    vec3 s = r.o - v0;
    float u = dot(s, p) * rcp;
    vec3 q = cross(s, e1);
    float v = dot(r.d, q) * rcp;
    t = dot(e2, q) * rcp;
    bary = vec2(u, v);
    return min(u, v) >= -RQ_EDGE_EPS && u + v <= 1.0 + RQ_EDGE_EPS && t > 0.0 && t < tmax;
}

#endif

#if RQ_STATS
// Per-invocation counters (RQ_STATS 1): the calling kernel reads and stores them.
uint rq_stat_nodes = 0u;       // internal nodes visited (TLAS and BLAS; RQ_BVH_WIDTH box tests each)
uint rq_stat_triangles = 0u;   // ray/triangle tests
uint rq_stat_instances = 0u;   // BLAS entries (instance transforms)
#define RQ_COUNT(c) ++c
#else
#define RQ_COUNT(c)
#endif
#if defined(RQ_COUNT_RAYS) && RQ_COUNT_RAYS
uint rq_rays = 0u;   // queries this invocation began
#endif

// Stochastic transparency (SCENE_HAS_ALPHA_BLEND): the path's seed and sample index, and the
// number of the ray being traced along it (rq_begin counts them). A trace_transmittance query
// multiplies rq_transmittance by (1 - alpha) at each BLEND surface instead of deciding it.
#if SCENE_HAS_ALPHA_BLEND
uint rq_blend_seed = 0u, rq_blend_index = 0u, rq_blend_ray = 0u;
bool rq_fractional = false;
float rq_transmittance = 1.0;
const float RQ_OPAQUE_BELOW = 1e-4;   // without roulette, a product this small blocks the ray (and ends its traversal)
const uint RQ_ROULETTE_SALT = 0x6C8E9CF5u;
#endif

// Seed this invocation's BLEND decisions with its path's generator (call it where the path's Rng
// starts; rays traced before are decided as for seed 0).
void rq_blend_begin(Rng r) {
#if SCENE_HAS_ALPHA_BLEND
    rq_blend_seed = r.state;
    rq_blend_index = r.index;
    rq_blend_ray = 0u;
#endif
}

#if SCENE_HAS_ALPHA_MASK || SCENE_HAS_ALPHA_BLEND
// Whether a hit at distance t, barycentrics b of scene triangle tri (material m, not OPAQUE) of
// `instance` counts: the MASK cutoff, and the BLEND decision of the current ray.
bool rq_alpha_passes(uint m, uint tri, uint instance, float t, vec2 b) {
    vec2 uv = triangle_uv(tri, b);
    if (!material_alpha_passes(m, uv)) return false;
#if SCENE_HAS_ALPHA_BLEND
    if (!material_blend_passes(m, uv, rq_blend_seed, rq_blend_index, alpha_blend_key(instance, m, t, rq_blend_ray)))
        return false;
#endif
    return true;
}
#endif

#if SCENE_HAS_ALPHA_BLEND
// trace_transmittance meets a BLEND surface (material m, scene triangle tri) at t: light through it
// is dimmed by (1 - alpha). Once the product falls below RQ_BLEND_ROULETTE, Russian roulette keeps
// it unbiased and ends most rays early: it goes on as RQ_BLEND_ROULETTE with probability product /
// RQ_BLEND_ROULETTE, else it is blocked. Without roulette a product below RQ_OPAQUE_BELOW blocks.
// Returns whether light still passes.
bool rq_blend_dims(uint m, uint tri, uint instance, float t, vec2 b) {
    rq_transmittance *= 1.0 - clamp(material_alpha(m, triangle_uv(tri, b)), 0.0, 1.0);
    // RQ_BLEND_ROULETTE is a literal: at 0 the compiler drops the branch (and its registers)
    if (RQ_BLEND_ROULETTE > 0.0 && rq_transmittance < RQ_BLEND_ROULETTE) {
        uint key = alpha_blend_key(instance, m, t, rq_blend_ray) ^ RQ_ROULETTE_SALT;   // not the coin's draw
        if (alpha_blend_u(rq_blend_seed, rq_blend_index, key) * RQ_BLEND_ROULETTE >= rq_transmittance) return false;
        rq_transmittance = RQ_BLEND_ROULETTE;
        return true;
    }
    return rq_transmittance >= RQ_OPAQUE_BELOW;
}
#endif

// Intersect the triangles of one leaf (BVH slots [first, first + count)); a hit nearer than tmax
// that counts (alpha) updates hit/tmax. The slot test is written out in the loop: a function per
// slot cost the hybrid's shadow pass 1% and its reflections 1.4% (benchmarks/RESULTS.md
// 2026-12-06, fifth run).
bool rq_leaf(RqRay r, uint instance, uint first, uint count, inout float tmax, inout Hit hit, bool any_hit) {
    bool found = false;
    for (uint s = first; s < first + count; ++s) {
        RQ_COUNT(rq_stat_triangles);
        vec4 v0 = rq_triangles[3u * s], v1 = rq_triangles[3u * s + 1u], v2 = rq_triangles[3u * s + 2u];
        float t;
        vec2 b;
        if (!rq_triangle(r, v0.xyz, v1.xyz, v2.xyz, tmax, t, b)) continue;
        uint prim = floatBitsToUint(v0.w);
#if SCENE_HAS_ALPHA_MASK || SCENE_HAS_ALPHA_BLEND
        uint alpha_mode = floatBitsToUint(v1.w);   // the slot's copy of its material's: opaque hits load nothing more
        if (alpha_mode != ALPHA_MODE_OPAQUE) {
            uint tri = scene_triangle(instance, prim);
            uint m = triangle_material(tri);
#if SCENE_HAS_ALPHA_BLEND
            if (rq_fractional && alpha_mode == ALPHA_MODE_BLEND) {
                if (rq_blend_dims(m, tri, instance, t, b)) continue;   // dimmed, not blocked
            } else
#endif
            if (!rq_alpha_passes(m, tri, instance, t, b)) continue;
        }
#endif
        tmax = t;
        hit.t = t;
        hit.barycentrics = b;
        hit.instance = instance;
        hit.primitive = prim;
        found = true;
        if (any_hit) break;
    }
    return found;
}

#if RQ_BVH_WIDTH == 8
// Intersect the triangles of BVH slots first + k for the set bits k of mask (a bvh8 leaf group).
bool rq_leaf_mask(RqRay r, uint instance, uint first, uint mask, inout float tmax, inout Hit hit, bool any_hit) {
    bool found = false;
    while (mask != 0u) {   // each run of consecutive set bits as one leaf, slots in ascending order
        uint k = uint(findLSB(mask));
        uint count = uint(findLSB(~(mask >> k)));
        mask &= ~(((1u << count) - 1u) << k);
        found = rq_leaf(r, instance, first + k, count, tmax, hit, any_hit) || found;
        if (found && any_hit) break;
    }
    return found;
}
#endif

RqRay rq_object_ray(vec3 o_render, vec3 d_render, uint instance) {
    vec4 m0 = scene_instances[instance].to_object[0], m1 = scene_instances[instance].to_object[1],
         m2 = scene_instances[instance].to_object[2];
    vec3 o = vec3(dot(m0, vec4(o_render, 1.0)), dot(m1, vec4(o_render, 1.0)), dot(m2, vec4(o_render, 1.0)));
    vec3 d = vec3(dot(m0.xyz, d_render), dot(m1.xyz, d_render), dot(m2.xyz, d_render));
    return rq_make_ray(o, d);
}

// A traversal work item: an internal node index, or (RQ_LEAF_BIT) a leaf: first slot in bits
// 0..27, count - 1 in bits 28..30 (leaves hold 1..8 triangles; a TLAS leaf is one instance).
#define RQ_LEAF_BIT 0x80000000u
#define RQ_NO_INSTANCE SCENE_NO_INSTANCE

uint rq_item(uint link, uint count) {
    return count == 0u ? link : (RQ_LEAF_BIT | ((count - 1u) << 28) | link);
}

// The state of one ray's traversal (rq_begin / rq_step): per-invocation globals, so that a kernel
// can interleave steps with other work (a persistent kernel refilling the lanes whose ray is done).
vec3 rq_o, rq_d;           // the ray in anchor space (render space - scene_shift)
float rq_tmax;             // the nearest hit so far, or the ray's end
bool rq_any_hit;
RqRay rq_r;                // the ray in the current level's space: rebuilt, not kept, on leaving a BLAS (fewer registers)
uint rq_instance;          // RQ_NO_INSTANCE in the TLAS
#if RQ_CONVEX_SKIP
uint rq_skip;              // the instance this ray does not enter
#endif
int rq_blas_base;          // stack depth when the current BLAS was entered
int rq_sp;
#if RQ_BVH_WIDTH == 8
#define RQ_STACK_ENTRIES (RQ_STACK_SIZE / 2)
uvec2 rq_stack[RQ_STACK_ENTRIES];   // node groups, and the TLAS's leaf groups (RQ_LEAF_GROUP)
uvec2 rq_group;            // node group: child base, hit children by rank << 8 | imask (>= 0x100: children left)
uvec2 rq_leaves;           // leaf group: first slot (TLAS: of the instance table), a bit per slot to test
#else
#define RQ_STACK_ENTRIES RQ_STACK_SIZE
uint rq_stack[RQ_STACK_ENTRIES];
uint rq_next;              // the node or leaf of the next step
#endif
bool rq_done;
bool rq_found;
Hit rq_hit;

// Start tracing (o, d) over (0, tmax_in), not entering instance `skip`. Unless rq_done (a scene
// without instances), call rq_step() until it returns false.
void rq_begin(vec3 o, vec3 d, float tmax_in, bool any_hit, uint skip) {
#if RQ_CONVEX_SKIP
    rq_skip = skip;
#endif
    rq_hit.t = tmax_in;
    rq_hit.barycentrics = vec2(0.0);
    rq_hit.instance = RQ_NO_INSTANCE;
    rq_hit.primitive = RQ_NO_INSTANCE;
    rq_found = false;
    rq_done = instance_count() == 0u;
    rq_o = o - render_shift();   // the TLAS and the instance transforms are in anchor space
    rq_d = d;
    rq_any_hit = any_hit;
    rq_tmax = min(tmax_in, 1e29);
    rq_r = rq_make_ray(rq_o, d);
    rq_instance = RQ_NO_INSTANCE;
    rq_blas_base = -1;
    rq_sp = 0;
#if RQ_BVH_WIDTH == 8
    rq_group = uvec2(0u, 0x100u);   // the root, as the one child of a group (imask 0: at the base)
    rq_leaves = uvec2(0u);
#else
    rq_next = 0u;
#endif
#if SCENE_HAS_ALPHA_BLEND
    ++rq_blend_ray;
#endif
#if defined(RQ_COUNT_RAYS) && RQ_COUNT_RAYS
    ++rq_rays;
#endif
}

void rq_begin(vec3 o, vec3 d, float tmax_in, bool any_hit) { rq_begin(o, d, tmax_in, any_hit, RQ_NO_INSTANCE); }

// Whether the ray passes by instance i without entering it.
bool rq_skips(uint i) {
#if RQ_CONVEX_SKIP
    return i == rq_skip;
#else
    return false;
#endif
}

// Move the ray into instance's object space: its BLAS is walked next (returns its root node).
uint rq_enter_instance(uint instance) {
    RQ_COUNT(rq_stat_instances);
    rq_instance = instance;
    rq_r = rq_object_ray(rq_o, rq_d, rq_instance);
    rq_blas_base = rq_sp;
    return scene_instances[rq_instance].info.y;
}

// Back to the TLAS once the stack is down to its depth at the BLAS entry.
void rq_leave_finished_instance() {
    if (rq_sp != rq_blas_base) return;
    rq_instance = RQ_NO_INSTANCE;
    rq_r = rq_make_ray(rq_o, rq_d);   // rebuilt, not kept, on leaving a BLAS (fewer registers)
    rq_blas_base = -1;
}

// The node of the level the ray is in.
#define RQ_FETCH(n, node) {                                                                      \
        uint base_ = (node) * uint(RQ_NODE_VEC4S);                                               \
        if (rq_instance == RQ_NO_INSTANCE) {                                                     \
            for (int k_ = 0; k_ < RQ_NODE_VEC4S; ++k_) n[k_] = rq_tlas_nodes[base_ + uint(k_)];  \
        } else {                                                                                 \
            for (int k_ = 0; k_ < RQ_NODE_VEC4S; ++k_) n[k_] = rq_blas_nodes[base_ + uint(k_)];  \
        } }

#if RQ_BVH_WIDTH == 8
#define RQ_LEAF_GROUP 0x80000000u   // a stack entry that is a TLAS leaf group

// Bits by slot -> bits by visiting rank for a ray of octant oct: rank r holds slot r ^ oct.
uint rq_ranks(uint slots, uint oct) {
    if ((oct & 1u) != 0u) slots = ((slots & 0x55u) << 1) | ((slots >> 1) & 0x55u);
    if ((oct & 2u) != 0u) slots = ((slots & 0x33u) << 2) | ((slots >> 2) & 0x33u);
    if ((oct & 4u) != 0u) slots = ((slots & 0x0Fu) << 4) | ((slots >> 4) & 0x0Fu);
    return slots;
}

// bit k set where direction component k is negative (the ray's octant)
uint rq_octant(vec3 inv) { return uint(inv.x < 0.0) | (uint(inv.y < 0.0) << 1) | (uint(inv.z < 0.0) << 2); }

// One step of a bvh8 traversal (see rq_step): a leaf group's triangles, one instance of a TLAS leaf
// group, or the current node group's nearest child node, whose hit children become the current
// groups (the rest of the old node group pushed).
bool rq_step() {
    if (rq_leaves.y != 0u) {
        if (rq_instance == RQ_NO_INSTANCE) {   // a TLAS leaf group: enter its first instance's BLAS
            uint u = rq_leaves.x + uint(findLSB(rq_leaves.y));
            rq_leaves.y &= rq_leaves.y - 1u;
            uint entered = floatBitsToUint(rq_tlas_nodes[u >> 2][u & 3u]);
            if (rq_skips(entered)) return true;   // the group's other instances, or its way out below
            if (rq_group.y >= 0x100u && rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = rq_group;
            if (rq_leaves.y != 0u && rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = uvec2(rq_leaves.x, rq_leaves.y | RQ_LEAF_GROUP);
            rq_group = uvec2(rq_enter_instance(entered), 0x100u);
            rq_leaves.y = 0u;
            return true;
        }
        rq_found = rq_leaf_mask(rq_r, rq_instance, rq_leaves.x, rq_leaves.y, rq_tmax, rq_hit, rq_any_hit) || rq_found;
        rq_leaves.y = 0u;
        if (rq_any_hit && rq_found) {
            rq_done = true;
            return false;
        }
    } else if (rq_group.y >= 0x100u) {
        RQ_COUNT(rq_stat_nodes);
        uint oct = rq_octant(rq_r.inv);
        uint rank = uint(findLSB(rq_group.y >> 8));
        rq_group.y &= ~(0x100u << rank);
        uint slot = rank ^ oct;
        vec4 n[RQ_NODE_VEC4S];   // header, (child base, triangle base, metas), x, y, z bytes
        RQ_FETCH(n, rq_group.x + uint(bitCount(rq_group.y & ((1u << slot) - 1u) & 0xFFu)))
        uint e = floatBitsToUint(n[0].w);
        vec3 scale = rq_grid_scale(e);
        uvec4 m = floatBitsToUint(n[1]), qx = floatBitsToUint(n[2]), qy = floatBitsToUint(n[3]), qz = floatBitsToUint(n[4]);
#if RQ_BVH8_FMA_BOX
        vec3 s, cn, cf;
        rq_qbox_consts(n[0].xyz, scale, rq_r.inv, rq_r.o, s, cn, cf);
        bvec3 neg = lessThan(rq_r.inv, vec3(0.0));
        vec4 t0 = rq_qbox4_fma(s, cn, cf, uvec3(qx.x, qy.x, qz.x), uvec3(qx.z, qy.z, qz.z), neg, rq_tmax);
        vec4 t1 = rq_qbox4_fma(s, cn, cf, uvec3(qx.y, qy.y, qz.y), uvec3(qx.w, qy.w, qz.w), neg, rq_tmax);
#else
        vec4 t0 = rq_qbox4(n[0].xyz, scale, uvec3(qx.x, qy.x, qz.x), uvec3(qx.z, qy.z, qz.z), rq_r.inv, rq_r.oi, rq_tmax);
        vec4 t1 = rq_qbox4(n[0].xyz, scale, uvec3(qx.y, qy.y, qz.y), uvec3(qx.w, qy.w, qz.w), rq_r.inv, rq_r.oi, rq_tmax);
#endif
        bvec4 hit0 = lessThan(t0, vec4(RQ_MISS)), hit1 = lessThan(t1, vec4(RQ_MISS));
        uvec4 h0 = uvec4(hit0) << uvec4(0u, 1u, 2u, 3u), h1 = uvec4(hit1) << uvec4(4u, 5u, 6u, 7u);
        uint hits = (h0.x | h0.y) | (h0.z | h0.w) | (h1.x | h1.y) | (h1.z | h1.w);
        uint imask = e >> 24;
        // each hit leaf's triangles: meta >> 5 of them from bit meta & 31 (internal and empty slots: meta 0)
        uvec4 meta0 = (uvec4(m.z) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu, meta1 = (uvec4(m.w) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu;
        uvec4 tri0 = mix(uvec4(0u), ((uvec4(1u) << (meta0 >> 5u)) - 1u) << (meta0 & 31u), hit0);
        uvec4 tri1 = mix(uvec4(0u), ((uvec4(1u) << (meta1 >> 5u)) - 1u) << (meta1 & 31u), hit1);
        uint triangles = (tri0.x | tri0.y) | (tri0.z | tri0.w) | (tri1.x | tri1.y) | (tri1.z | tri1.w);
        if (rq_group.y >= 0x100u && rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = rq_group;
        rq_group = uvec2(m.x, (rq_ranks(hits & imask, oct) << 8) | imask);
        rq_leaves = uvec2(m.y, triangles);
        if (rq_leaves.y != 0u) return true;
    }
    if (rq_group.y >= 0x100u) return true;
    rq_leave_finished_instance();
    if (rq_sp == 0) {
        rq_done = true;
        return false;
    }
    uvec2 g = rq_stack[--rq_sp];
    bool leaf_group = (g.y & RQ_LEAF_GROUP) != 0u;
    rq_group = leaf_group ? uvec2(0u) : g;
    rq_leaves = leaf_group ? uvec2(g.x, g.y & ~RQ_LEAF_GROUP) : uvec2(0u);
    return true;
}

#else
// One step of the ray's traversal: one node fetch, one BLAS entry or one leaf, so that a loop
// of steps from one call site keeps a warp's lanes in step. Returns false once the ray is done
// (rq_done): rq_found and rq_hit then hold its result; do not call it again before rq_begin. A
// TLAS leaf switches the ray to the instance's object space and the walk continues in its BLAS;
// popping back to the stack depth at entry switches back.
bool rq_step() {
    if ((rq_next & RQ_LEAF_BIT) == 0u) {
        RQ_COUNT(rq_stat_nodes);
        vec4 n[RQ_NODE_VEC4S];   // the node, from the level the ray is in
        RQ_FETCH(n, rq_next)
#if RQ_BVH_WIDTH == 4 && RQ_BVH_QUANTIZED   // header, lo/hi x y bytes, lo/hi z bytes, items
        uvec4 c = floatBitsToUint(n[3]);
        vec4 t = rq_box4q(n[0], floatBitsToUint(n[1]), floatBitsToUint(n[2].xy), c, rq_r.inv, rq_r.oi, rq_tmax);
#elif RQ_BVH_WIDTH == 4                     // lo.x, hi.x, lo.y, hi.y, lo.z, hi.z of 4 children, items
        vec4 t = rq_box4(n[0], n[1], n[2], n[3], n[4], n[5], rq_r.inv, rq_r.oi, rq_tmax);
        uvec4 c = floatBitsToUint(n[6]);
#endif
#if RQ_BVH_WIDTH == 4
        // sort the children near to far (misses are RQ_MISS, last): a 5-comparator network
        RQ_ORDER(t.x, c.x, t.y, c.y); RQ_ORDER(t.z, c.z, t.w, c.w);
        RQ_ORDER(t.x, c.x, t.z, c.z); RQ_ORDER(t.y, c.y, t.w, c.w);
        RQ_ORDER(t.y, c.y, t.z, c.z);
        if (t.x < RQ_MISS) {
            if (t.w < RQ_MISS && rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = c.w;   // far first: popped last
            if (t.z < RQ_MISS && rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = c.z;
            if (t.y < RQ_MISS && rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = c.y;
            rq_next = c.x;
            return true;
        }
#else                                       // min0 link0, max0 count0, min1 link1, max1 count1
        float t0 = rq_box(n[0].xyz, n[1].xyz, rq_r.inv, rq_r.oi, rq_tmax);
        float t1 = rq_box(n[2].xyz, n[3].xyz, rq_r.inv, rq_r.oi, rq_tmax);
        uint c0 = rq_item(floatBitsToUint(n[0].w), floatBitsToUint(n[1].w));
        uint c1 = rq_item(floatBitsToUint(n[2].w), floatBitsToUint(n[3].w));
        bool go0 = t0 >= 0.0, go1 = t1 >= 0.0;
        if (go0 && go1) {
            bool near0 = t0 <= t1;
            if (rq_sp < RQ_STACK_ENTRIES) rq_stack[rq_sp++] = near0 ? c1 : c0;
            rq_next = near0 ? c0 : c1;
            return true;
        }
        if (go0 || go1) {
            rq_next = go0 ? c0 : c1;
            return true;
        }
#endif
    } else if (rq_instance == RQ_NO_INSTANCE) {   // a TLAS leaf: enter the instance's BLAS
        if (!rq_skips(rq_next & 0x0FFFFFFFu)) {
            rq_next = rq_enter_instance(rq_next & 0x0FFFFFFFu);
            return true;
        }
    } else {
        rq_found = rq_leaf(rq_r, rq_instance, rq_next & 0x0FFFFFFFu, ((rq_next >> 28) & 7u) + 1u, rq_tmax, rq_hit, rq_any_hit)
                   || rq_found;
        if (rq_any_hit && rq_found) {
            rq_done = true;
            return false;
        }
    }
    rq_leave_finished_instance();   // this BLAS is done: back to the TLAS and the render-space ray
    if (rq_sp == 0) {
        rq_done = true;
        return false;
    }
    rq_next = rq_stack[--rq_sp];
    return true;
}
#endif

bool rq_trace(vec3 o, vec3 d, float tmax_in, bool any_hit, uint skip, out Hit hit) {
    rq_begin(o, d, tmax_in, any_hit, skip);
    if (!rq_done) {
        while (rq_step()) {}
    }
    hit = rq_hit;
    return rq_found;
}

bool trace_closest(vec3 o, vec3 d, float tmax, uint skip, out Hit hit) { return rq_trace(o, d, tmax, false, skip, hit); }
bool trace_closest(vec3 o, vec3 d, float tmax, out Hit hit) { return rq_trace(o, d, tmax, false, RQ_NO_INSTANCE, hit); }

bool trace_occluded(vec3 o, vec3 d, float tmax, uint skip) {
    Hit h;
    return rq_trace(o, d, tmax, true, skip, h);
}
bool trace_occluded(vec3 o, vec3 d, float tmax) { return trace_occluded(o, d, tmax, RQ_NO_INSTANCE); }

float trace_transmittance(vec3 o, vec3 d, float tmax, uint skip) {
#if SCENE_HAS_ALPHA_BLEND
    rq_fractional = true;
    rq_transmittance = 1.0;
    bool blocked = trace_occluded(o, d, tmax, skip);
    rq_fractional = false;
    return blocked ? 0.0 : rq_transmittance;
#else
    return trace_occluded(o, d, tmax, skip) ? 0.0 : 1.0;
#endif
}
float trace_transmittance(vec3 o, vec3 d, float tmax) { return trace_transmittance(o, d, tmax, RQ_NO_INSTANCE); }
