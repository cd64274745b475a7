// Parent links from the children (after rotations moved subtrees), for another bottom-up round.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 8) readonly buffer Children { uvec2 children[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 10) writeonly buffer InternalParent { uint internal_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 11) writeonly buffer LeafParent { uint leaf_parent[]; };
#include "lbvh_common.glsl"
uniform uint n;
void main() {
    FOR_EACH(i, n - 1u) {
        uvec2 ch = children[i];
        if ((ch.x & LEAF_FLAG) != 0u) leaf_parent[ch.x & ~LEAF_FLAG] = i; else internal_parent[ch.x] = i;
        if ((ch.y & LEAF_FLAG) != 0u) leaf_parent[ch.y & ~LEAF_FLAG] = i; else internal_parent[ch.y] = i;
    }
}
