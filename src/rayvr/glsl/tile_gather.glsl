// Workgroups that gather their work from several tiles: where a trace decision leaves a few
// pixels of work scattered over every tile (foveation's dither), a workgroup per tile would hold
// a warp for each few. A workgroup of RAY_GROUP_SIZE (at most 32) invocations covers TILE_GATHER
// ray_group tiles side by side (workgroups x * TILE_GATHER + k, glsl/ray_group.glsl), finds the
// pixels with work among them (tile_gather_wants, which the includer defines), and works through
// them RAY_GROUP_SIZE at a time in the tiles' order. Every invocation calls tile_gather() in
// uniform control flow (it holds barriers), then:
//   for (uint b = 0u, n = tile_gather(); b < n; ++b) if (tile_gather_pixel(b, p)) work(p);
// (The includer defines TILE_GATHER first; without it this file declares nothing: an #include is
// expanded even inside a false #if.)
#pragma once
#include "ray_group.glsl"
#ifdef TILE_GATHER

bool tile_gather_wants(ivec3 p);   // the includer's: pixel p (perhaps past the image) has work

shared uint s_tile_gather[TILE_GATHER];   // bit i of word k: lane i of tile k has work

uvec3 tile_gather_tile(uint k) { return uvec3(gl_WorkGroupID.x * uint(TILE_GATHER) + k, gl_WorkGroupID.yz); }

// The batches of RAY_GROUP_SIZE pixels the workgroup works through.
uint tile_gather() {
    uint lane = gl_LocalInvocationIndex;
    for (uint k = lane; k < uint(TILE_GATHER); k += uint(RAY_GROUP_SIZE)) s_tile_gather[k] = 0u;
    barrier();
    for (uint k = 0u; k < uint(TILE_GATHER); ++k)
        if (tile_gather_wants(ray_group_pixel_of(tile_gather_tile(k), lane))) atomicOr(s_tile_gather[k], 1u << lane);
    barrier();
    uint n = 0u;
    for (uint k = 0u; k < uint(TILE_GATHER); ++k) n += uint(bitCount(s_tile_gather[k]));
    return (n + uint(RAY_GROUP_SIZE) - 1u) / uint(RAY_GROUP_SIZE);
}

// The bit position of the n-th (from 0) set bit of m (which has more than n).
uint tile_gather_nth_bit(uint m, uint n) {
    uint at = 0u;
    for (uint w = 16u; w > 0u; w >>= 1u) {
        uint low = m & ((1u << w) - 1u);
        uint c = uint(bitCount(low));
        if (n >= c) { n -= c; m >>= w; at += w; } else m = low;
    }
    return at;
}

// This invocation's pixel of batch b; false past the last pixel with work.
bool tile_gather_pixel(uint b, out ivec3 p) {
    uint j = b * uint(RAY_GROUP_SIZE) + gl_LocalInvocationIndex;
    p = ivec3(0);
    for (uint k = 0u; k < uint(TILE_GATHER); ++k) {
        uint m = s_tile_gather[k];
        uint c = uint(bitCount(m));
        if (j < c) {
            p = ray_group_pixel_of(tile_gather_tile(k), tile_gather_nth_bit(m, j));
            return true;
        }
        j -= c;
    }
    return false;
}
#endif
