// Blit: resample layer min(z, source layers - 1) of `src` into `dst` (scale and format change).
#include "dst_image.glsl"
uniform sampler2DArray src;

void main() {
    ivec3 p;
    if (!dst_texel(p)) return;
    int layers = textureSize(src, 0).z;
    vec2 uv = (vec2(p.xy) + 0.5) / vec2(imageSize(dst).xy);
    store_dst(p, textureLod(src, vec3(uv, float(min(p.z, layers - 1))), 0.0));
}
