// One level of the greedy BVH2 -> "bvh8" collapse (rayvr/scene/bvh_gpu.py, layout of bvh8.py).
// Thread w in [level_begin, level_end) turns BVH2 node wide_source[w] into BVH8 node w
// (wide_collapse.glsl's open_children), places its children in direction slots (greedily the
// child and slot of the largest score, as bvh8.direction_slots: the child's centre offset from the
// node's centre, in units of the node's size on a 2^-12 grid, dotted with the slot's direction),
// takes adjacent indices for its internal children (in slot order) and a range of the BVH8's
// triangle slots for its leaves (one atomicAdd each), copies its leaves' triangles there, and
// writes its 80 B node with 8-bit boxes on the node's grid (bvh_wide.quantize_grid's rule; each
// decoded plane checked to hold the exact box) and, per node, uvec4 x 2 source child slots
// (0xFFFFFFFF when empty) + uvec4 x 2 items (bvh_wide's: node index or packed leaf).
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0 + 0) readonly buffer Bvh2Nodes { vec4 bvh2_nodes[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 1) buffer WideSource { uint wide_source[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 2) buffer WideCounter { uint wide_counter[2]; };   // nodes, triangles
layout(std430, binding = RAYVR_PASS_SSBO_0 + 3) writeonly buffer WideNodes { vec4 wide_nodes[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 4) writeonly buffer WideLinks { uvec4 wide_links[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 5) readonly buffer TriIn { vec4 tri_in[]; };     // the BVH2's slots
layout(std430, binding = RAYVR_PASS_SSBO_0 + 6) writeonly buffer TriOut { vec4 tri_out[]; };  // the BVH8's
#include "lbvh_common.glsl"
uniform uint level_begin;
uniform uint level_end;
uniform uint bvh2_node_base;   // added to the BVH2's node links by its build (subtracted here)
uniform uint bvh2_tri_base;    // added to its leaf links
#define WIDE 8
#include "wide_collapse.glsl"

float pow2(int e) { return uintBitsToFloat(uint(e + 127) << 23); }

// The least e in [-126, 127] with origin + 255 * 2^e >= top in float32 (as the shader decodes).
int grid_exponent(float origin, float top) {
    float extent = top - origin;
    if (!(extent > 0.0)) return -126;
    int e;
    frexp(extent / 255.0, e);   // extent / 255 < 2^e
    e = clamp(e - 1, -126, 127);
    while (e < 127 && origin + 255.0 * pow2(e) < top) ++e;
    return e;
}

uint plane_lo(float origin, float scale, float lo) {
    float q = clamp(floor((lo - origin) / scale), 0.0, 255.0);
    while (q > 0.0 && origin + q * scale > lo) q -= 1.0;
    return uint(q);
}

uint plane_hi(float origin, float scale, float hi) {
    float q = clamp(ceil((hi - origin) / scale), 0.0, 255.0);
    while (q < 255.0 && origin + q * scale < hi) q += 1.0;
    return uint(q);
}

void main() {
    FOR_EACH(i, level_end - level_begin) {
        uint w = level_begin + i;
        vec3 lo[8], hi[8];
        uint link[8], count[8], slot[8];
        uint children = open_children(wide_source[w], lo, hi, link, count, slot);
        vec3 node_lo = vec3(3e38), node_hi = vec3(-3e38);
        uint live = 0u;
        for (uint k = 0u; k < children; ++k) {
            if (lo[k].x >= 1e29) continue;
            live |= 1u << k;
            node_lo = min(node_lo, lo[k]);
            node_hi = max(node_hi, hi[k]);
        }
        // direction slots
        vec3 centre = node_lo + node_hi;
        vec3 dirs[8];
        float extent = max(max(node_hi.x - node_lo.x, node_hi.y - node_lo.y), max(node_hi.z - node_lo.z, 1e-30));
        for (uint k = 0u; k < children; ++k) dirs[k] = (lo[k] + hi[k] - centre) / extent;
        uint child_of[8] = uint[8](8u, 8u, 8u, 8u, 8u, 8u, 8u, 8u);   // per slot; 8: empty
        uint free_children = live, free_slots = 0xFFu;
        while (free_children != 0u) {
            float best = -3e38;
            uint bk = 0u, bs = 0u;
            for (uint k = 0u; k < children; ++k) {
                if ((free_children >> k & 1u) == 0u) continue;
                for (uint s = 0u; s < 8u; ++s) {
                    if ((free_slots >> s & 1u) == 0u) continue;
                    vec3 d = vec3((s & 1u) != 0u ? 1.0 : -1.0, (s & 2u) != 0u ? 1.0 : -1.0, (s & 4u) != 0u ? 1.0 : -1.0);
                    float score = round(dot(dirs[k], d) * 4096.0);
                    if (score > best) { best = score; bk = k; bs = s; }
                }
            }
            child_of[bs] = bk;
            free_children &= ~(1u << bk);
            free_slots &= ~(1u << bs);
        }
        uint inner = 0u, tris = 0u, imask = 0u;
        for (uint s = 0u; s < 8u; ++s) {
            uint k = child_of[s];
            if (k == 8u) continue;
            if (count[k] == 0u) { inner += 1u; imask |= 1u << s; } else { tris += count[k]; }
        }
        uint next = inner > 0u ? atomicAdd(wide_counter[0], inner) : 0u;
        uint tri_base = tris > 0u ? atomicAdd(wide_counter[1], tris) : 0u;
        uint child_base = next;
        // the grid
        ivec3 e = ivec3(grid_exponent(node_lo.x, node_hi.x), grid_exponent(node_lo.y, node_hi.y),
                        grid_exponent(node_lo.z, node_hi.z));
        vec3 scale = vec3(pow2(e.x), pow2(e.y), pow2(e.z));
        uint q_lo[6] = uint[6](0u, 0u, 0u, 0u, 0u, 0u), q_hi[6] = uint[6](0u, 0u, 0u, 0u, 0u, 0u);   // axis * 2 + half
        uint metas[2] = uint[2](0u, 0u);
        uint src[8], items[8];
        uint offset = 0u;
        for (uint s = 0u; s < 8u; ++s) {
            uint k = child_of[s];
            uint shift = 8u * (s & 3u), half_ = s >> 2;
            src[s] = EMPTY_SLOT;
            items[s] = 0u;
            if (k == 8u) {   // empty: the inverted box, meta 0
                for (uint a = 0u; a < 3u; ++a) q_lo[2u * a + half_] |= 255u << shift;
                continue;
            }
            src[s] = slot[k];
            for (uint a = 0u; a < 3u; ++a) {
                q_lo[2u * a + half_] |= plane_lo(node_lo[a], scale[a], lo[k][a]) << shift;
                q_hi[2u * a + half_] |= plane_hi(node_lo[a], scale[a], hi[k][a]) << shift;
            }
            if (count[k] == 0u) {
                wide_source[next] = link[k] - bvh2_node_base;
                items[s] = next++;
            } else {
                items[s] = LEAF_ITEM_BIT | ((count[k] - 1u) << 28) | link[k];
                metas[half_] |= ((count[k] << 5) | offset) << shift;
                uint first = link[k] - bvh2_tri_base;
                for (uint j = 0u; j < count[k]; ++j) {
                    uint from = 3u * (first + j), to = 3u * (tri_base + offset + j);
                    tri_out[to] = tri_in[from];
                    tri_out[to + 1u] = tri_in[from + 1u];
                    tri_out[to + 2u] = tri_in[from + 2u];
                }
                offset += count[k];
            }
        }
        uint ew = uint(e.x + 127) | (uint(e.y + 127) << 8) | (uint(e.z + 127) << 16) | (imask << 24);
        uint o = 5u * w;
        wide_nodes[o + 0u] = vec4(node_lo, uintBitsToFloat(ew));
        wide_nodes[o + 1u] = uintBitsToFloat(uvec4(child_base, tri_base, metas[0], metas[1]));
        for (uint a = 0u; a < 3u; ++a)
            wide_nodes[o + 2u + a] = uintBitsToFloat(uvec4(q_lo[2u * a], q_lo[2u * a + 1u], q_hi[2u * a], q_hi[2u * a + 1u]));
        wide_links[4u * w] = uvec4(src[0], src[1], src[2], src[3]);
        wide_links[4u * w + 1u] = uvec4(src[4], src[5], src[6], src[7]);
        wide_links[4u * w + 2u] = uvec4(items[0], items[1], items[2], items[3]);
        wide_links[4u * w + 3u] = uvec4(items[4], items[5], items[6], items[7]);
    }
}
