// Shared by the BVH2 -> wide collapses (bvh4_collapse.comp, bvh8_collapse.comp; rayvr/scene/bvh_gpu.py):
// a wide node is a BVH2 node whose children are opened greedily, the internal child of largest box
// area first, until it has WIDE children or none is left to open. The kernel declares
// bvh2_nodes (the BVH2's vec4s) and the uniform bvh2_node_base before including this.
#define EMPTY_SLOT 0xFFFFFFFFu
#define LEAF_ITEM_BIT 0x80000000u

float half_area(vec3 lo, vec3 hi) {
    vec3 d = hi - lo;
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

// BVH2 child slot s (2 * node + side) into wide child k of the arrays lo, hi, link, count, slot
#define LOAD_CHILD(k, s) {                                                          \
        vec4 a_ = bvh2_nodes[2u * (s)], b_ = bvh2_nodes[2u * (s) + 1u];             \
        slot[k] = (s); lo[k] = a_.xyz; hi[k] = b_.xyz;                              \
        link[k] = floatBitsToUint(a_.w); count[k] = floatBitsToUint(b_.w); }

// BVH2 node `node`'s children opened into up to WIDE: each one's box, link and count (bvh.py's
// child slot) and source child slot (2 * node + side); returns how many. A child whose box is at
// 1e30 is a single-leaf root's empty slot.
uint open_children(uint node, out vec3 lo[WIDE], out vec3 hi[WIDE], out uint link[WIDE], out uint count[WIDE],
                   out uint slot[WIDE]) {
    for (uint k = 0u; k < uint(WIDE); ++k) { lo[k] = hi[k] = vec3(0.0); link[k] = count[k] = 0u; slot[k] = EMPTY_SLOT; }
    LOAD_CHILD(0u, 2u * node)
    LOAD_CHILD(1u, 2u * node + 1u)
    uint children = 2u;
    while (children < uint(WIDE)) {   // open the internal child of largest area
        int best = -1;
        float best_area = -1.0;
        for (uint k = 0u; k < children; ++k) {
            float area = half_area(lo[k], hi[k]);
            if (count[k] == 0u && lo[k].x < 1e29 && area > best_area) { best = int(k); best_area = area; }
        }
        if (best < 0) break;
        uint opened = link[best] - bvh2_node_base;
        LOAD_CHILD(uint(best), 2u * opened)
        LOAD_CHILD(children, 2u * opened + 1u)
        children += 1u;
    }
    return children;
}
