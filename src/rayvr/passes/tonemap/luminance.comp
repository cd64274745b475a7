// Auto exposure, stage 1: each workgroup sums log2 luminance of its pixels into one partial.
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;

#include "color.glsl"
uniform sampler2DArray src;
layout(std430) writeonly buffer Partials { vec2 partials[]; };

const float BLACK_LUMINANCE = 1e-3;

shared vec2 s_sum[256];

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = textureSize(src, 0);
    vec2 v = vec2(0.0);
    if (all(lessThan(p, size))) {
        vec3 c = texelFetch(src, p, 0).rgb;
        float l = luminance(c);
        // Black pixels (sky, shadow, noise) would drag the log average down and over-expose the rest.
        if (!(isnan(l) || isinf(l)) && l > BLACK_LUMINANCE) v = vec2(log2(l), 1.0);
    }
    uint i = gl_LocalInvocationIndex;
    s_sum[i] = v;
    barrier();
    for (uint s = 128u; s > 0u; s >>= 1u) {
        if (i < s) s_sum[i] += s_sum[i + s];
        barrier();
    }
    if (i == 0u) {
        uvec3 n = gl_NumWorkGroups;
        uint g = gl_WorkGroupID.x + n.x * (gl_WorkGroupID.y + n.y * gl_WorkGroupID.z);
        partials[g] = s_sum[0];
    }
}
