// Accumulate: progressive running mean of `src` in an rgba32f sum (Kahan-compensated), all views
// in one dispatch. acc_count = frames in the sum after this one; acc_count == 1 restarts it. A
// non-finite sample is added as 0 (counted: nonfinite.glsl), so it cannot poison the mean.
#include "nonfinite.glsl"
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
uniform sampler2DArray src;
layout(rgba32f) uniform image2DArray acc_sum;
layout(rgba32f) uniform image2DArray acc_compensation;
layout(rgba32f) writeonly uniform image2DArray dst;
uniform uint acc_count;
uniform bool acc_add;   // false once max_frames is reached: the mean stays frozen

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    precise vec4 sum;
    if (acc_count <= 1u) {
        sum = nonfinite_scrub(texelFetch(src, p, 0));
        imageStore(acc_sum, p, sum);
        imageStore(acc_compensation, p, vec4(0.0));
    } else if (acc_add) {
        // Kahan summation: `precise` stops the compiler from simplifying the compensation away.
        precise vec4 c = imageLoad(acc_compensation, p);
        precise vec4 y = nonfinite_scrub(texelFetch(src, p, 0)) - c;
        precise vec4 s = imageLoad(acc_sum, p);
        sum = s + y;
        c = (sum - s) - y;
        imageStore(acc_sum, p, sum);
        imageStore(acc_compensation, p, c);
    } else {
        sum = imageLoad(acc_sum, p);
    }
    imageStore(dst, p, sum / float(max(acc_count, 1u)));
}
