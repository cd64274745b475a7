// Looking Glass quilt: view v of a texture array goes to tile (v % cols, v / cols), with tile
// row 0 at the bottom (GL's y), so view 0 is the bottom-left tile. Tiles past the view count
// are cleared to black. One dispatch: (ceil(w/8), ceil(h/8), cols * rows).
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2DArray src;
layout(QUILT_IMAGE_FORMAT, binding = 0) writeonly uniform image2D dst;

uniform ivec2 grid;       // cols, rows
uniform int view_count;

void main() {
    ivec2 size = textureSize(src, 0).xy;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    int v = int(gl_GlobalInvocationID.z);
    if (p.x >= size.x || p.y >= size.y) return;
    ivec2 tile = ivec2(v % grid.x, v / grid.x);
    vec4 c = v < view_count ? texelFetch(src, ivec3(p, v), 0) : vec4(0.0, 0.0, 0.0, 1.0);
    imageStore(dst, tile * size + p, c);
}
