// Re-encode rendered views for an OpenXR swapchain whose format a raw copy cannot fill:
// decode sRGB-encoded input to linear and/or encode linear to sRGB, one layer per view.
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2DArray src;
layout(STAGING_FORMAT, binding = 0) writeonly uniform image2DArray dst;

uniform int decode_srgb;   // input holds sRGB-encoded values
uniform int encode_srgb;   // output must hold sRGB-encoded values

vec3 srgb_to_linear_exact(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

vec3 linear_to_srgb_exact(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec2 size = textureSize(src, 0).xy;
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 c = texelFetch(src, p, 0);
    if (decode_srgb != 0) c.rgb = srgb_to_linear_exact(c.rgb);
    if (encode_srgb != 0) c.rgb = linear_to_srgb_exact(c.rgb);
    imageStore(dst, p, c);
}
