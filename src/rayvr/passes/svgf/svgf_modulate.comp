// SVGF stage 4, remodulation: the filtered illumination of each lobe times its albedo, plus the
// G-buffer's emission; where nothing was drawn, the input (the background) as it came. Only with
// no a-trous iteration: otherwise the last one remodulates (svgf_atrous.comp, SVGF_FINAL).
#include "svgf_common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

uniform sampler2DArray svgf_diffuse_in;
uniform SVGF_ILLUM_SAMPLER src_illum;
layout(rgba16f) writeonly uniform image2DArray dst;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    if (!svgf_has_geometry(gbuf_fetch_effect(p))) {
        imageStore(dst, p, svgf_background(svgf_diffuse_in, p));
        return;
    }
    SvgfIllum illum = texelFetch(src_illum, p, 0);
    vec3 c = svgf_color(p, svgf_illum_diffuse(illum).rgb, svgf_illum_specular(illum).rgb);
    imageStore(dst, p, vec4(to_half_range(c), 1.0));
}
