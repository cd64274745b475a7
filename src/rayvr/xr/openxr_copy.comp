// Re-encode rendered views for an OpenXR swapchain whose format a raw copy cannot fill:
// decode sRGB-encoded input to linear and/or encode linear to sRGB, one layer per view.
#include "color.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2DArray src;
layout(STAGING_FORMAT, binding = 0) writeonly uniform image2DArray dst;

uniform int decode_srgb;   // input holds sRGB-encoded values
uniform int encode_srgb;   // output must hold sRGB-encoded values

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec2 size = textureSize(src, 0).xy;
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 c = texelFetch(src, p, 0);
    if (decode_srgb != 0) c.rgb = srgb_to_linear(c.rgb);
    if (encode_srgb != 0) c.rgb = srgb_encode(clamp(c.rgb, 0.0, 1.0));
    imageStore(dst, p, c);
}
