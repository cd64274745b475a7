// A pixel (or a tile) of a view in one word, as the pixel lists hold it (glsl/pixel_list.glsl,
// glsl/work_tiles.glsl): x (13 bits) | y (13 bits) << 13 | view (6 bits) << 26: up to 8192 px and 64 views.
#pragma once
uint pixel_list_pack(ivec3 p) { return uint(p.x) | (uint(p.y) << 13u) | (uint(p.z) << 26u); }
ivec3 pixel_list_unpack(uint w) { return ivec3(w & 0x1FFFu, (w >> 13u) & 0x1FFFu, w >> 26u); }
