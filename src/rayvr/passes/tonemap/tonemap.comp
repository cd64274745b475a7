// HDR radiance -> display: exposure (fixed stops, or auto from the frame's mean log luminance),
// an operator (ACES fit, Reinhard, linear clamp) and sRGB encoding into rgba8.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "color.glsl"
#include "nonfinite.glsl"

uniform sampler2DArray src;
layout(rgba8) writeonly uniform image2DArray dst;

#if AUTO_EXPOSURE
layout(std430) readonly buffer Exposure { float exposure_scale; };
#endif

uniform float exposure_stops;

vec3 aces_fit(vec3 x) {   // Narkowicz 2015, fit of the ACES RRT+ODT
    x *= 0.6;
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 tonemap(vec3 c) {
#if TONEMAP_OPERATOR == 0
    return aces_fit(c);
#elif TONEMAP_OPERATOR == 1
    return c / (1.0 + c);
#else
    return clamp(c, 0.0, 1.0);
#endif
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    vec4 c = texelFetch(src, p, 0);
    float scale = exp2(exposure_stops);
#if AUTO_EXPOSURE
    scale *= exposure_scale;
#endif
    vec3 hdr = max(nonfinite_scrub(c.rgb * scale), vec3(0.0));
    vec3 ldr = tonemap(hdr);
#if OUTPUT_SRGB
    ldr = srgb_encode(ldr);
#endif
    imageStore(dst, p, vec4(ldr, 1.0));
}
