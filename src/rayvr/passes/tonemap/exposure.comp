// Auto exposure, stage 2: one workgroup sums the partials and moves the exposure towards
// key / exp2(mean log2 luminance), adapting over frames.
layout(local_size_x = 256) in;

layout(std430) buffer Exposure { float exposure_scale; };
layout(std430) readonly buffer Partials { vec2 partials[]; };

uniform uint partial_count;
uniform float key;
uniform float adaptation;   // 1: jump to the target this frame

shared vec2 s_sum[256];

void main() {
    uint i = gl_LocalInvocationIndex;
    vec2 acc = vec2(0.0);
    for (uint k = i; k < partial_count; k += 256u) acc += partials[k];
    s_sum[i] = acc;
    barrier();
    for (uint s = 128u; s > 0u; s >>= 1u) {
        if (i < s) s_sum[i] += s_sum[i + s];
        barrier();
    }
    if (i == 0u) {
        float mean = s_sum[0].y > 0.0 ? s_sum[0].x / s_sum[0].y : 0.0;
        float target = key / exp2(mean);
        float prev = exposure_scale;
        bool fresh = !(prev > 0.0) || isinf(prev);
        exposure_scale = fresh ? target : mix(prev, target, adaptation);
    }
}
