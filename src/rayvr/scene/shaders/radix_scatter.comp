// Radix sort pass, step 2: stable scatter of keys and payloads to their scanned digit offsets.
// Each tile walks its keys in chunks of 256; a key's rank among equal digits of its chunk is
// counted from the chunk's digits in shared memory (stable), then the chunk's counts advance
// the tile's running offsets.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 2) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 3) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 5) readonly buffer ScanSums { uint scan_sums[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 6) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 7) writeonly buffer ValsOut { uint vals_out[]; };
#include "lbvh_common.glsl"
uniform uint n;
uniform uint shift;
uniform uint blocks;
shared uint s_digit[256];
shared uint s_run[256];
shared uint s_count[256];
void main() {
    uint l = gl_LocalInvocationID.x, tile = gl_WorkGroupID.x;
    uint o = l * blocks + tile;
    s_run[l] = offsets[o] + scan_sums[o / SCAN_BLOCK];   // the scan's block sums are added here
    s_count[l] = 0u;
    uint first = tile * TILE;
    uint last = min(first + TILE, n);
    for (uint base = first; base < last; base += WG) {
        uint i = base + l;
        bool valid = i < last;
        uint key = valid ? keys_in[i] : 0u;
        uint digit = valid ? (key >> shift) & 255u : 256u;
        s_digit[l] = digit;
        barrier();
        uint rank = 0u;
        for (uint j = 0u; j < l; ++j)
            rank += s_digit[j] == digit ? 1u : 0u;
        if (valid) {
            uint pos = s_run[digit] + rank;
            keys_out[pos] = key;
            vals_out[pos] = vals_in[i];
            atomicAdd(s_count[digit], 1u);
        }
        barrier();
        s_run[l] += s_count[l];
        s_count[l] = 0u;
        barrier();
    }
}
