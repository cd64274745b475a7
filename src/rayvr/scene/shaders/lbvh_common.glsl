// Shared by the GPU LBVH kernels (rayvr/scene/bvh_gpu.py): bindings and grid-stride helpers.
// Buffers bind at RAYVR_PASS_SSBO_0 + k; each kernel names the k it uses.
#define LBVH_SSBO(k) (RAYVR_PASS_SSBO_0 + (k))
#define WG 256u
#define LEAF_FLAG 0x80000000u

// Grid-stride loop over [0, n): the dispatch is capped at 65535 groups.
#define FOR_EACH(i, n) for (uint i = gl_GlobalInvocationID.x; i < (n); i += gl_NumWorkGroups.x * WG)

// Floats as uints that order like the floats (for atomicMin/Max on bounds).
uint float_to_ordered(float f) {
    uint b = floatBitsToUint(f);
    return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}
float ordered_to_float(uint u) {
    return uintBitsToFloat((u & 0x80000000u) != 0u ? u & 0x7FFFFFFFu : ~u);
}

#ifdef HAS_TRI_IN
vec3 load_vertex(uint t, uint v) {   // triangles: float[9] per triangle
    uint b = 9u * t + 3u * v;
    return vec3(tri_in[b], tri_in[b + 1u], tri_in[b + 2u]);
}
// The centre of the triangle's box (as bvh.py's centroids)
vec3 box_centre(uint t) {
    vec3 a = load_vertex(t, 0u), b = load_vertex(t, 1u), c = load_vertex(t, 2u);
    return (min(min(a, b), c) + max(max(a, b), c)) * 0.5;
}
#endif
