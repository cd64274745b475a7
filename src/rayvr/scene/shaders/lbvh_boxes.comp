// One thread per sorted slot: gathers its triangle into the BVH-ordered triangle array
// (3 vec4, vertex 0's w = the original triangle index, as GpuScene packs it), stores its box,
// then climbs: at each parent the second thread to arrive (atomic counter) merges both
// children's boxes and goes on; the first one stops.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer TriIn { float tri_in[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 3) readonly buffer Vals { uint vals[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 8) readonly buffer Children { uvec2 children[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 10) readonly buffer InternalParent { uint internal_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 11) readonly buffer LeafParent { uint leaf_parent[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 12) coherent buffer Arrivals { uint arrivals[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 13) coherent buffer LeafBox { vec4 leaf_box[]; };   // lo, hi per slot
layout(std430, binding = RAYVR_PASS_SSBO_0 + 14) coherent buffer NodeBox { vec4 node_box[]; };   // lo, hi per internal node
layout(std430, binding = RAYVR_PASS_SSBO_0 + 15) writeonly buffer TriOut { vec4 tri_out[]; };
#define HAS_TRI_IN
#include "lbvh_common.glsl"
uniform uint n;

void child_box(uint c, out vec3 lo, out vec3 hi) {
    uint k = c & ~LEAF_FLAG;
    if ((c & LEAF_FLAG) != 0u) { lo = leaf_box[2u * k].xyz; hi = leaf_box[2u * k + 1u].xyz; }
    else { lo = node_box[2u * k].xyz; hi = node_box[2u * k + 1u].xyz; }
}

void main() {
    FOR_EACH(slot, n) {
        uint t = vals[slot];
        vec3 a = load_vertex(t, 0u), b = load_vertex(t, 1u), c = load_vertex(t, 2u);
        tri_out[3u * slot] = vec4(a, uintBitsToFloat(t));
        tri_out[3u * slot + 1u] = vec4(b, 0.0);
        tri_out[3u * slot + 2u] = vec4(c, 0.0);
        leaf_box[2u * slot] = vec4(min(min(a, b), c), 0.0);
        leaf_box[2u * slot + 1u] = vec4(max(max(a, b), c), 0.0);
        uint node = leaf_parent[slot];
        while (true) {
            memoryBarrierBuffer();
            if (atomicAdd(arrivals[node], 1u) == 0u) break;
            memoryBarrierBuffer();
            uvec2 ch = children[node];
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
