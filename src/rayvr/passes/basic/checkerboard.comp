// Checkerboard: squares of `cell` pixels; the pattern shifts by one cell per layer, so views differ.
#include "dst_image.glsl"
uniform vec4 color_a;
uniform vec4 color_b;
uniform int cell;

void main() {
    ivec3 p;
    if (!dst_texel(p)) return;
    int parity = (p.x / cell + p.y / cell + p.z) & 1;
    store_dst(p, parity == 0 ? color_a : color_b);
}
