// The GPU node layout of bvh.py (64 B: both children's boxes, link and count in the w's) for
// every kept internal node, at its compacted index (the exclusive scan of `keep`). A child of at
// most LEAF_SIZE slots becomes a leaf (link = first slot, count = slots). node_base / tri_base
// offset node and leaf links (several BLASes in one buffer).
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) readonly buffer NewIndex { uint new_index[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 6) writeonly buffer Nodes { vec4 nodes[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 8) readonly buffer Children { uvec2 children[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 9) readonly buffer Ranges { uvec2 ranges[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 13) readonly buffer LeafBox { vec4 leaf_box[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 14) readonly buffer NodeBox { vec4 node_box[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 16) readonly buffer Sizes { uint sizes[]; };
#include "lbvh_common.glsl"
uniform uint n;
uniform uint node_base;
uniform uint tri_base;

void emit_child(uint out_at, uint c) {
    uint k = c & ~LEAF_FLAG;
    vec3 lo, hi;
    uint link, count;
    if ((c & LEAF_FLAG) != 0u) {
        lo = leaf_box[2u * k].xyz; hi = leaf_box[2u * k + 1u].xyz;
        link = tri_base + k; count = 1u;
    } else {
        lo = node_box[2u * k].xyz; hi = node_box[2u * k + 1u].xyz;
        count = sizes[k];
        if (count <= uint(LEAF_SIZE)) link = tri_base + ranges[k].x;   // never rotated: still a slot range
        else { link = node_base + new_index[k]; count = 0u; }
    }
    nodes[out_at] = vec4(lo, uintBitsToFloat(link));
    nodes[out_at + 1u] = vec4(hi, uintBitsToFloat(count));
}

void main() {
    FOR_EACH(i, n - 1u) {
        if (i != 0u && sizes[i] <= uint(LEAF_SIZE)) continue;
        uint o = 4u * new_index[i];
        uvec2 ch = children[i];
        emit_child(o, ch.x);
        emit_child(o + 2u, ch.y);
    }
}
