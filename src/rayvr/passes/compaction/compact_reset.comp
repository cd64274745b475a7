// Empties the pixel lists before compaction: count 0, indirect args (0, 1, 1).
layout(local_size_x = 1) in;
layout(std430) buffer ShadowList { uint shadow_header[4]; };
layout(std430) buffer ReflectionList { uint reflection_header[4]; };
layout(std430) buffer PathList { uint path_header[4]; };
void main() {
    shadow_header[0] = 0u; shadow_header[1] = 0u; shadow_header[2] = 1u; shadow_header[3] = 1u;
    reflection_header[0] = 0u; reflection_header[1] = 0u; reflection_header[2] = 1u; reflection_header[3] = 1u;
    path_header[0] = 0u; path_header[1] = 0u; path_header[2] = 1u; path_header[3] = 1u;
}
