// One thread per sorted slot: gathers its triangle into the BVH-ordered triangle array
// (3 vec4, vertex 0's w = the original triangle index, as GpuScene packs it), stores its box,
// then climbs: at each parent the second thread to arrive (atomic counter) merges both
// children's boxes and goes on; the first one stops.
// ROTATIONS: there, with both subtrees final, the thread also tries Kensler's tree rotations
// (swap one child with a grandchild under the other child) and keeps the one that shrinks
// that child's box most: the SAH cost falls by the area saved. Only subtrees of more than
// LEAF_SIZE triangles are rotated into or through, so every subtree the emitter turns into a
// leaf keeps its contiguous slot range.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer TriIn { float tri_in[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 3) readonly buffer Vals { uint vals[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 8) coherent buffer Children { uvec2 children[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 10) readonly buffer InternalParent { uint internal_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 11) readonly buffer LeafParent { uint leaf_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 12) coherent buffer Arrivals { uint arrivals[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 13) coherent buffer LeafBox { vec4 leaf_box[]; };   // lo, hi per slot
layout(std430, binding = RAYVR_PASS_SSBO_0 + 14) coherent buffer NodeBox { vec4 node_box[]; };   // lo, hi per internal node
layout(std430, binding = RAYVR_PASS_SSBO_0 + 15) writeonly buffer TriOut { vec4 tri_out[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 16) coherent buffer Sizes { uint sizes[]; };       // triangles per internal node
#define HAS_TRI_IN
#include "lbvh_common.glsl"
uniform uint n;
uniform uint first_round;   // later rounds (rotations only) keep the gathered triangles and leaf boxes

void child_box(uint c, out vec3 lo, out vec3 hi) {
    uint k = c & ~LEAF_FLAG;
    if ((c & LEAF_FLAG) != 0u) { lo = leaf_box[2u * k].xyz; hi = leaf_box[2u * k + 1u].xyz; }
    else { lo = node_box[2u * k].xyz; hi = node_box[2u * k + 1u].xyz; }
}

uint child_size(uint c) { return (c & LEAF_FLAG) != 0u ? 1u : sizes[c]; }
float half_area(vec3 lo, vec3 hi) { vec3 d = max(hi - lo, vec3(0.0)); return d.x * d.y + d.y * d.z + d.z * d.x; }

#if ROTATIONS
// Best swap of `other` (the node's other child) with a child of `inner`: returns the area of
// inner's new box (or `best` when nothing beats it) and the grandchild slot to swap (0/1).
float try_rotate(uint inner, uint other, float best, inout int pick) {
    if ((inner & LEAF_FLAG) != 0u || sizes[inner] <= uint(LEAF_SIZE)) return best;
    uvec2 g = children[inner];
    vec3 olo, ohi, lo0, hi0, lo1, hi1;
    child_box(other, olo, ohi);
    child_box(g.x, lo0, hi0);
    child_box(g.y, lo1, hi1);
    uint so = child_size(other);
    float a0 = half_area(min(olo, lo1), max(ohi, hi1));   // other replaces grandchild 0
    float a1 = half_area(min(olo, lo0), max(ohi, hi0));   // other replaces grandchild 1
    if (a0 < best && so + child_size(g.y) > uint(LEAF_SIZE)) { best = a0; pick = 0; }
    if (a1 < best && so + child_size(g.x) > uint(LEAF_SIZE)) { best = a1; pick = 1; }
    return best;
}

void rotate(uint node, uvec2 ch) {
    vec3 lo, hi;
    child_box(ch.x, lo, hi);
    float area_x = (ch.x & LEAF_FLAG) != 0u ? 0.0 : half_area(lo, hi);
    child_box(ch.y, lo, hi);
    float area_y = (ch.y & LEAF_FLAG) != 0u ? 0.0 : half_area(lo, hi);
    int pick_y = -1, pick_x = -1;
    float gain_y = area_y - try_rotate(ch.y, ch.x, area_y * 0.999, pick_y);   // x moves under y
    float gain_x = area_x - try_rotate(ch.x, ch.y, area_x * 0.999, pick_x);   // y moves under x
    if (pick_y < 0 && pick_x < 0) return;
    bool under_y = pick_y >= 0 && (pick_x < 0 || gain_y >= gain_x);
    uint inner = under_y ? ch.y : ch.x, other = under_y ? ch.x : ch.y;
    int pick = under_y ? pick_y : pick_x;
    uvec2 g = children[inner];
    uint moved = pick == 0 ? g.x : g.y;
    uvec2 ng = pick == 0 ? uvec2(other, g.y) : uvec2(g.x, other);
    children[inner] = ng;
    children[node] = under_y ? uvec2(moved, inner) : uvec2(inner, moved);
    vec3 lo0, hi0, lo1, hi1;
    child_box(ng.x, lo0, hi0);
    child_box(ng.y, lo1, hi1);
    node_box[2u * inner] = vec4(min(lo0, lo1), 0.0);
    node_box[2u * inner + 1u] = vec4(max(hi0, hi1), 0.0);
    sizes[inner] = child_size(ng.x) + child_size(ng.y);
    memoryBarrierBuffer();
}
#endif

void main() {
    FOR_EACH(slot, n) {
        if (first_round != 0u) {
            uint t = vals[slot];
            vec3 a = load_vertex(t, 0u), b = load_vertex(t, 1u), c = load_vertex(t, 2u);
            tri_out[3u * slot] = vec4(a, uintBitsToFloat(t));
            tri_out[3u * slot + 1u] = vec4(b, 0.0);
            tri_out[3u * slot + 2u] = vec4(c, 0.0);
            leaf_box[2u * slot] = vec4(min(min(a, b), c), 0.0);
            leaf_box[2u * slot + 1u] = vec4(max(max(a, b), c), 0.0);
        }
        uint node = leaf_parent[slot];
        while (true) {
            memoryBarrierBuffer();
            if (atomicAdd(arrivals[node], 1u) == 0u) break;
            memoryBarrierBuffer();
            uvec2 ch = children[node];
#if ROTATIONS
            if (sizes[node] > uint(LEAF_SIZE)) {
                rotate(node, ch);
                ch = children[node];
            }
#endif
            vec3 lo0, hi0, lo1, hi1;
            child_box(ch.x, lo0, hi0);
            child_box(ch.y, lo1, hi1);
            node_box[2u * node] = vec4(min(lo0, lo1), 0.0);
            node_box[2u * node + 1u] = vec4(max(hi0, hi1), 0.0);
            if (node == 0u) break;
            node = internal_parent[node];
        }
    }
}
