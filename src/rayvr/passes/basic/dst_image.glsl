// The output image of a basic pass: a 2D array (one layer per view) bound to image unit 0.
// DST_FORMAT is the GLSL format qualifier, DST_UINT 1 for unsigned-integer formats.
#pragma once
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;   // COMPUTE_GROUP of passes/_common.py
#if DST_UINT
layout(DST_FORMAT) uniform writeonly uimage2DArray dst;
void store_dst(ivec3 p, vec4 c) { imageStore(dst, p, uvec4(c)); }
#else
layout(DST_FORMAT) uniform writeonly image2DArray dst;
void store_dst(ivec3 p, vec4 c) { imageStore(dst, p, c); }
#endif

// This invocation's texel (x, y, layer), or false when it lies outside the image.
bool dst_texel(out ivec3 p) {
    p = ivec3(gl_GlobalInvocationID);
    return all(lessThan(p, imageSize(dst)));
}
