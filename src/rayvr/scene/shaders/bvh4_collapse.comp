// One level of the greedy BVH2 -> "bvh4" collapse (rayvr/scene/bvh_gpu.py, layout of bvh_wide.py).
// Thread w in [level_begin, level_end) turns BVH2 node wide_source[w] into BVH4 node w
// (wide_collapse.glsl's open_children). The internal children left become the next level's BVH4
// nodes, given adjacent indices by one atomicAdd on the counter; leaves become leaf items
// (LEAF_ITEM_BIT | count - 1 << 28 | first slot); empty slots get the 1e30 box and item 0.
// Writes the 112 B node (vec4 min.x, max.x, min.y, max.y, min.z, max.z, uvec4 item) and, per
// node, uvec4 source child slots (2 * BVH2 node + side, 0xFFFFFFFF when empty) + uvec4 items.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 0) readonly buffer Bvh2Nodes { vec4 bvh2_nodes[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 1) buffer WideSource { uint wide_source[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 2) buffer WideCounter { uint wide_counter; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 3) writeonly buffer WideNodes { vec4 wide_nodes[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) writeonly buffer WideLinks { uvec4 wide_links[]; };
#include "lbvh_common.glsl"
uniform uint level_begin;
uniform uint level_end;
uniform uint bvh2_node_base;   // added to the BVH2's node links by its build (subtracted here)
#define WIDE 4
#include "wide_collapse.glsl"

#define EMPTY_BOX 1e30

void main() {
    FOR_EACH(i, level_end - level_begin) {
        uint w = level_begin + i;
        vec3 lo[4], hi[4];
        uint link[4], count[4], slot[4];
        uint children = open_children(wide_source[w], lo, hi, link, count, slot);
        uint inner = 0u;
        for (uint k = 0u; k < children; ++k) inner += uint(count[k] == 0u && lo[k].x < 1e29);
        uint next = inner > 0u ? atomicAdd(wide_counter, inner) : 0u;
        uvec4 items = uvec4(0u);
        for (uint k = 0u; k < 4u; ++k) {
            bool live = k < children && lo[k].x < 1e29;
            if (!live) {
                slot[k] = EMPTY_SLOT;
                lo[k] = hi[k] = vec3(EMPTY_BOX);
            } else if (count[k] > 0u) {
                items[k] = LEAF_ITEM_BIT | ((count[k] - 1u) << 28) | link[k];
            } else {
                wide_source[next] = link[k] - bvh2_node_base;
                items[k] = next++;
            }
        }
        uint o = 7u * w;
        wide_nodes[o + 0u] = vec4(lo[0].x, lo[1].x, lo[2].x, lo[3].x);
        wide_nodes[o + 1u] = vec4(hi[0].x, hi[1].x, hi[2].x, hi[3].x);
        wide_nodes[o + 2u] = vec4(lo[0].y, lo[1].y, lo[2].y, lo[3].y);
        wide_nodes[o + 3u] = vec4(hi[0].y, hi[1].y, hi[2].y, hi[3].y);
        wide_nodes[o + 4u] = vec4(lo[0].z, lo[1].z, lo[2].z, lo[3].z);
        wide_nodes[o + 5u] = vec4(hi[0].z, hi[1].z, hi[2].z, hi[3].z);
        wide_nodes[o + 6u] = uintBitsToFloat(items);
        wide_links[2u * w] = uvec4(slot[0], slot[1], slot[2], slot[3]);
        wide_links[2u * w + 1u] = items;
    }
}
