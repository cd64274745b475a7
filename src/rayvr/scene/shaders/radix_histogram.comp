// Radix sort pass, step 1: per tile of TILE keys, the count of each 8-bit digit at `shift`,
// stored digit-major (hist[digit * blocks + tile]) so one exclusive scan gives scatter offsets.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 2) readonly buffer Keys { uint keys[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) writeonly buffer Hist { uint hist[]; };
#include "lbvh_common.glsl"
uniform uint n;
uniform uint shift;
uniform uint blocks;
shared uint s_count[256];
void main() {
    uint l = gl_LocalInvocationID.x, tile = gl_WorkGroupID.x;
    s_count[l] = 0u;
    barrier();
    uint first = tile * TILE;
    uint last = min(first + TILE, n);
    for (uint i = first + l; i < last; i += WG)
        atomicAdd(s_count[(keys[i] >> shift) & 255u], 1u);
    barrier();
    hist[l * blocks + tile] = s_count[l];
}
