// Exclusive prefix sum of uint data[0, n) in place, in three dispatches (STAGE):
// 1: each group scans SCAN_BLOCK elements and stores its total in sums[group];
// 2: one group scans sums[0, groups) in place (sums[groups] = the grand total);
// 3 (optional): data[i] += sums[i / SCAN_BLOCK]  (the radix scatter adds it itself).
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) buffer Data { uint data[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 5) buffer Sums { uint sums[]; };
#include "lbvh_common.glsl"
uniform uint n;
uniform uint groups;
shared uint s_sum[256];

uint scan_shared(uint l, uint v) {   // exclusive scan of one value per thread; returns the total in s_sum[255]
    s_sum[l] = v;
    barrier();
    for (uint d = 1u; d < WG; d <<= 1u) {
        uint add = l >= d ? s_sum[l - d] : 0u;
        barrier();
        s_sum[l] += add;
        barrier();
    }
    return s_sum[l] - v;
}

void main() {
    uint l = gl_LocalInvocationID.x;
#if STAGE == 1
    const uint PER = SCAN_BLOCK / WG;
    uint base = gl_WorkGroupID.x * SCAN_BLOCK + l * PER;
    uint v[PER];
    uint total = 0u;
    for (uint k = 0u; k < PER; ++k) {
        v[k] = base + k < n ? data[base + k] : 0u;
        total += v[k];
    }
    uint run = scan_shared(l, total);
    for (uint k = 0u; k < PER; ++k) {
        if (base + k < n) data[base + k] = run;
        run += v[k];
    }
    if (l == WG - 1u) sums[gl_WorkGroupID.x] = run;
#elif STAGE == 2
    uint per = (groups + WG - 1u) / WG;
    uint base = l * per;
    uint total = 0u;
    for (uint k = base; k < min(base + per, groups); ++k)
        total += sums[k];
    uint run = scan_shared(l, total);
    for (uint k = base; k < min(base + per, groups); ++k) {
        uint v = sums[k];
        sums[k] = run;
        run += v;
    }
    if (l == WG - 1u) sums[groups] = run;
#else
    FOR_EACH(i, n) data[i] += sums[i / SCAN_BLOCK];
#endif
}
