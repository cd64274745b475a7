// Stage 4 of a probe update (rayvr.passes.ProbeGI; records in probe_rays.glsl): a workgroup per
// probe, an invocation per ray. Each takes its ray's light from stages 2 and 3 (what needed no ray
// plus the direct light its shadow ray let through) and its distance; then each texel of the
// probe's irradiance (cosine-weighted) and depth-moment (cosine^50 weighted, Majercik et al. 2019)
// maps is blended with its previous value by the hysteresis.
// Border texels repeat their octahedral opposite's interior texel, computed the same way, so
// no second pass copies them. Results go to the pass's outputs and to the history the next
// update reads (probe_*_tex are the previous update's history).
#define PROBE_GI 1
#include "probe_rays.glsl"
#include "nonfinite.glsl"
#include "color.glsl"

layout(local_size_x = PROBE_RAYS) in;
layout(rgba16f) writeonly uniform image2DArray irradiance_out;    // what the lookups sample
layout(rgba32f) writeonly uniform image2DArray irradiance_next;   // the history, blended in float32
layout(rg32f) writeonly uniform image2DArray depth_out;
layout(rg32f) writeonly uniform image2DArray depth_next;
layout(rg32f) writeonly uniform image2DArray state_out;
layout(rg32f) writeonly uniform image2DArray state_next;

uniform sampler2DArray probe_state_tex;   // the previous update's (backface fraction, active)
uniform float probe_hysteresis;   // weight of the previous value (0: replace it)
uniform int probe_history;        // 0: no previous update (its textures are undefined)

const float PROBE_DEPTH_SHARPNESS = 50.0;
const float PROBE_DEPTH_MIN_COS = 0.5;     // 0.5^50 ~ 1e-15
const float PROBE_BACKFACE_LIMIT = 0.25;   // probes seeing more back faces than this are inside geometry

shared vec4 ray_radiance[PROBE_RAYS];   // rgb; a: distance for the depth moments
shared vec3 ray_direction[PROBE_RAYS];
shared uint backfaces;

// The interior texel whose value texel `t` of a `tile`-texel octahedral tile holds.
ivec2 border_source(ivec2 t, int tile) {
    int e = tile - 1;
    bool bx = t.x == 0 || t.x == e;
    bool by = t.y == 0 || t.y == e;
    if (bx && by) return ivec2(t.x == 0 ? e - 1 : 1, t.y == 0 ? e - 1 : 1);
    if (bx) return ivec2(t.x == 0 ? 1 : e - 1, e - t.y);
    if (by) return ivec2(e - t.x, t.y == 0 ? 1 : e - 1);
    return t;
}

vec3 texel_direction(ivec2 t, int tile) {
    return oct_decode((vec2(t - 1) + 0.5) / float(tile - 2) * 2.0 - 1.0);
}

void main() {
    uint probe = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    uint ray = gl_LocalInvocationID.x;
    bool live = probe < probe_info.z;   // no early return: barrier() below needs every invocation
    if (ray == 0u) backfaces = 0u;
    float max_depth = probe_volumes[live ? probe_volume_of(probe) : 0u].lo.w;
    vec3 dir = probe_ray_direction(ray);
    barrier();

    vec4 radiance = vec4(0.0, 0.0, 0.0, max_depth);
    if (live) {
        uint i = probe * uint(PROBE_RAYS) + ray;
        vec4 direct = probe_rays[i].direct;   // a: the shadow ray's visibility
        radiance = probe_rays[i].radiance;
        radiance.rgb = nonfinite_scrub(radiance.rgb + direct.rgb * direct.a);
        if (probe_rays[i].ids.w == PROBE_RAY_BACKFACE) atomicAdd(backfaces, 1u);
    }
    ray_radiance[ray] = radiance;
    ray_direction[ray] = dir;
    memoryBarrierShared();
    barrier();
    if (!live) return;

    ivec2 tile = probe_tile(probe);
    bool history = probe_history != 0;
    float h = history ? probe_hysteresis : 0.0;
    // Inside geometry (too many back faces): the probe drops out of every lookup. The flag also goes
    // to the irradiance texels' alpha, so that a lookup reads it with the irradiance, not by a
    // fetch of its own before it (one dependent fetch less in every lookup).
    float fraction = float(backfaces) / float(PROBE_RAYS);
    if (history) fraction = mix(fraction, texelFetch(probe_state_tex, ivec3(tile, 0), 0).x, h);
    float enabled = fraction < PROBE_BACKFACE_LIMIT ? 1.0 : 0.0;   // ('active' is a reserved word)
    const int IT = PROBE_IRRADIANCE_TILE;
    for (uint k = ray; k < uint(IT * IT); k += uint(PROBE_RAYS)) {
        ivec2 t = ivec2(int(k) % IT, int(k) / IT);
        ivec2 src = border_source(t, IT);
        vec3 n = texel_direction(src, IT);
        vec3 sum = vec3(0.0);
        float total = 0.0;
        for (int r = 0; r < PROBE_RAYS; ++r) {
            float w = max(0.0, dot(n, ray_direction[r]));
            sum += w * ray_radiance[r].rgb;
            total += w;
        }
        // sum(L cos) / sum(cos) estimates irradiance / pi
        vec3 e = total > 0.0 ? RAYVR_PI * sum / total : vec3(0.0);
        if (history) e = mix(e, texelFetch(probe_irradiance_tex, ivec3(tile * IT + src, 0), 0).rgb, h);
        ivec3 texel = ivec3(tile * IT + t, 0);
        imageStore(irradiance_out, texel, vec4(to_half_range(e), enabled));
        imageStore(irradiance_next, texel, vec4(e, enabled));
    }
    const int DT = PROBE_DEPTH_TILE;
    for (uint k = ray; k < uint(DT * DT); k += uint(PROBE_RAYS)) {
        ivec2 t = ivec2(int(k) % DT, int(k) / DT);
        ivec2 src = border_source(t, DT);
        vec3 n = texel_direction(src, DT);
        vec2 sum = vec2(0.0);
        float total = 0.0;
        for (int r = 0; r < PROBE_RAYS; ++r) {
            float c = dot(n, ray_direction[r]);
            if (c < PROBE_DEPTH_MIN_COS) continue;   // weight below 1e-15: not worth the pow
            float w = pow(c, PROBE_DEPTH_SHARPNESS);
            float d = ray_radiance[r].a;
            sum += w * vec2(d, d * d);
            total += w;
        }
        vec2 moments = total > 1e-12 ? sum / total : vec2(max_depth, max_depth * max_depth);
        if (history) moments = mix(moments, texelFetch(probe_depth_tex, ivec3(tile * DT + src, 0), 0).xy, h);
        ivec3 texel = ivec3(tile * DT + t, 0);
        imageStore(depth_out, texel, vec4(moments, 0.0, 0.0));
        imageStore(depth_next, texel, vec4(moments, 0.0, 0.0));
    }
    if (ray == 0u) {
        vec4 state = vec4(fraction, enabled, 0.0, 0.0);
        imageStore(state_out, ivec3(tile, 0), state);
        imageStore(state_next, ivec3(tile, 0), state);
    }
}
