// Per-effect pixel lists: every pixel whose effect needs shadow rays goes to the shadow list,
// every pixel that needs reflection rays to the reflection list, PATH_TRACED pixels to the path
// list when the graph has a path tracer (glsl/pixel_list.glsl layout); with COMPACT_EVERY_SURFACE
// every pixel goes to the path list. With TRACE_DECISION the pixels the trace decision reconstructs
// from others go to none (glsl/trace_decision.glsl).
// One global atomic per workgroup and list; the indirect group count grows as the list fills.
#define GBUF_READER 1
#include "gbuffer.glsl"
#include "pixel_list.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(std430) buffer ShadowList {
    uint shadow_count; uint shadow_dispatch[3]; uint shadow_items[];
};
layout(std430) buffer ReflectionList {
    uint reflection_count; uint reflection_dispatch[3]; uint reflection_items[];
};
layout(std430) buffer PathList {
    uint path_count; uint path_dispatch[3]; uint path_items[];
};

shared uint s_count[3];
shared uint s_base[3];

void main() {
    if (gl_LocalInvocationIndex == 0u) { s_count[0] = 0u; s_count[1] = 0u; s_count[2] = 0u; }
    barrier();

    ivec3 p = ivec3(gl_GlobalInvocationID);
    ivec3 size = textureSize(gbuf_effect, 0);
    uint effect = GBUF_NO_GEOMETRY;
    if (all(lessThan(p, size))) effect = gbuf_effect_at(p);
    bool geo = effect != GBUF_NO_GEOMETRY;
    // With a path tracer in the graph, PATH_TRACED pixels get only its list; else they count as
    // REFLECTIONS (the most the hybrid passes offer).
    bool traces = all(lessThan(p, size));
#if TRACE_DECISION
    traces = traces && !decision_reconstructed(p);
#endif
    bool wants_path = COMPACT_PATHS != 0 && traces && (COMPACT_EVERY_SURFACE != 0 || (geo && effect == EFFECT_PATH_TRACED));
    bool wants_shadow = traces && geo && effect >= EFFECT_SHADOWS && !wants_path && COMPACT_EVERY_SURFACE == 0;
    bool wants_reflection = COMPACT_REFLECTIONS != 0 && traces && geo && effect >= EFFECT_REFLECTIONS && !wants_path
                            && COMPACT_EVERY_SURFACE == 0;

    uint local_shadow = wants_shadow ? atomicAdd(s_count[0], 1u) : 0u;
    uint local_reflection = wants_reflection ? atomicAdd(s_count[1], 1u) : 0u;
    uint local_path = wants_path ? atomicAdd(s_count[2], 1u) : 0u;
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        if (s_count[0] > 0u) {
            s_base[0] = atomicAdd(shadow_count, s_count[0]);
            atomicAdd(shadow_dispatch[0], pixel_list_new_groups(s_base[0], s_count[0]));
        }
        if (s_count[1] > 0u) {
            s_base[1] = atomicAdd(reflection_count, s_count[1]);
            atomicAdd(reflection_dispatch[0], pixel_list_new_groups(s_base[1], s_count[1]));
        }
        if (s_count[2] > 0u) {
            s_base[2] = atomicAdd(path_count, s_count[2]);
            atomicAdd(path_dispatch[0], pixel_list_new_groups(s_base[2], s_count[2]));
        }
    }
    barrier();
    if (wants_shadow) shadow_items[s_base[0] + local_shadow] = pixel_list_pack(p);
    if (wants_reflection) reflection_items[s_base[1] + local_reflection] = pixel_list_pack(p);
    if (wants_path) path_items[s_base[2] + local_path] = pixel_list_pack(p);
}
