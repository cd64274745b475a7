// Karras 2012: internal node i of the sorted codes finds its key range and split in parallel.
// children[i]: two child references (LEAF_FLAG | slot, or an internal node index);
// ranges[i]: its slots [first, last] (sizes[i] their count); parents of both kinds of nodes; keep[i] = 1 when the node
// stays an internal node of the output (more than LEAF_SIZE slots; smaller ones become leaves).
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 2) readonly buffer Keys { uint keys[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) writeonly buffer Keep { uint keep[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 8) writeonly buffer Children { uvec2 children[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 9) writeonly buffer Ranges { uvec2 ranges[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 10) writeonly buffer InternalParent { uint internal_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 11) writeonly buffer LeafParent { uint leaf_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 16) writeonly buffer Sizes { uint sizes[]; };
#include "lbvh_common.glsl"
uniform uint n;

// Length of the common prefix of the codes at slots i and j (ties broken by the slot index);
// -1 outside [0, n).
int delta(int i, int j) {
    if (j < 0 || j >= int(n)) return -1;
    uint a = keys[i], b = keys[j];
    if (a == b) return 32 + 31 - findMSB(uint(i ^ j));
    return 31 - findMSB(a ^ b);
}

void main() {
    FOR_EACH(u, n - 1u) {
        int i = int(u);
        int d = delta(i, i + 1) - delta(i, i - 1) >= 0 ? 1 : -1;
        int dmin = delta(i, i - d);
        int lmax = 2;
        while (delta(i, i + lmax * d) > dmin) lmax *= 2;
        int len = 0;
        for (int t = lmax / 2; t >= 1; t /= 2)
            if (delta(i, i + (len + t) * d) > dmin) len += t;
        int j = i + len * d;
        int dnode = delta(i, j);
        int s = 0;
        int t = len;
        do {
            t = (t + 1) / 2;
            if (delta(i, i + (s + t) * d) > dnode) s += t;
        } while (t > 1);
        int gamma = i + s * d + min(d, 0);
        int first = min(i, j), last = max(i, j);
        uint left = first == gamma ? LEAF_FLAG | uint(gamma) : uint(gamma);
        uint right = last == gamma + 1 ? LEAF_FLAG | uint(gamma + 1) : uint(gamma + 1);
        children[u] = uvec2(left, right);
        ranges[u] = uvec2(first, last);
        sizes[u] = uint(last - first) + 1u;
        keep[u] = (u == 0u || uint(last - first) + 1u > uint(LEAF_SIZE)) ? 1u : 0u;
        if ((left & LEAF_FLAG) != 0u) leaf_parent[gamma] = u; else internal_parent[gamma] = u;
        if ((right & LEAF_FLAG) != 0u) leaf_parent[gamma + 1] = u; else internal_parent[gamma + 1] = u;
    }
}
