// Centroid bounds of all triangles: a workgroup reduction, then one atomic per group and axis.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer TriIn { float tri_in[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 1) buffer Bounds { uint bounds[6]; };  // min xyz, max xyz (ordered)
#define HAS_TRI_IN
#include "lbvh_common.glsl"
uniform uint n;
shared vec3 s_lo[256];
shared vec3 s_hi[256];
void main() {
    vec3 lo = vec3(3.0e38), hi = vec3(-3.0e38);
    FOR_EACH(i, n) {
        vec3 c = box_centre(i);
        lo = min(lo, c);
        hi = max(hi, c);
    }
    uint l = gl_LocalInvocationID.x;
    s_lo[l] = lo;
    s_hi[l] = hi;
    barrier();
    for (uint s = WG / 2u; s > 0u; s >>= 1u) {
        if (l < s) {
            s_lo[l] = min(s_lo[l], s_lo[l + s]);
            s_hi[l] = max(s_hi[l], s_hi[l + s]);
        }
        barrier();
    }
    if (l < 3u) {
        atomicMin(bounds[l], float_to_ordered(s_lo[0][l]));
        atomicMax(bounds[3u + l], float_to_ordered(s_hi[0][l]));
    }
}
