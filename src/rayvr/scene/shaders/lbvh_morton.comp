// 30-bit Morton codes of triangle centroids on a cubic grid over the centroid bounds
// (one scale for all axes, as bvh.py: per-axis scales stretch flat scenes); payload = index.
layout(local_size_x = 256) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) readonly buffer TriIn { float tri_in[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 1) readonly buffer Bounds { uint bounds[6]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 2) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = RAYVR_PASS_SSBO_0 + 3) writeonly buffer Vals { uint vals[]; };
#define HAS_TRI_IN
#include "lbvh_common.glsl"
uniform uint n;

uint expand_bits(uint v) {   // 10 bits -> every third bit
    v = (v * 0x00010001u) & 0xFF0000FFu;
    v = (v * 0x00000101u) & 0x0F00F00Fu;
    v = (v * 0x00000011u) & 0xC30C30C3u;
    v = (v * 0x00000005u) & 0x49249249u;
    return v;
}

void main() {
    vec3 lo = vec3(ordered_to_float(bounds[0]), ordered_to_float(bounds[1]), ordered_to_float(bounds[2]));
    vec3 hi = vec3(ordered_to_float(bounds[3]), ordered_to_float(bounds[4]), ordered_to_float(bounds[5]));
    vec3 ext = hi - lo;
    float scale = 1023.0 / max(max(ext.x, max(ext.y, ext.z)), 1e-30);
    FOR_EACH(i, n) {
        vec3 c = box_centre(i);
        uvec3 q = uvec3(clamp((c - lo) * scale, vec3(0.0), vec3(1023.0)));
        keys[i] = (expand_bits(q.x) << 2) | (expand_bits(q.y) << 1) | expand_bits(q.z);
        vals[i] = i;
    }
}
