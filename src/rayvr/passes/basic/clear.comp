// Clear: every texel of layer z gets colors[min(z, color_count - 1)].
#include "dst_image.glsl"
uniform vec4 colors[RAYVR_MAX_VIEWS];
uniform int color_count;

void main() {
    ivec3 p;
    if (!dst_texel(p)) return;
    store_dst(p, colors[min(p.z, color_count - 1)]);
}
