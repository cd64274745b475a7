// Lights of rayvr.scene.GpuScene: KHR_lights_punctual (point, spot, directional) and the table of
// emissive triangles, sampled by power (area x luminance of emission; degenerate ones left out).
//
//   LightSample sample_light(vec3 p, vec3 u)        one light sample for shading point p, u in [0,1)^3
//   uint punctual_light_count()                     (SCENE_HAS_PUNCTUAL_LIGHTS)
//   LightSample eval_punctual_light(uint i, vec3 p) light i alone, weight without selection pdf
//   float emissive_light_pdf(SurfacePoint q, uint instance, vec3 p)  solid-angle pdf with which
//       sample_light would pick point q on an emissive triangle (for MIS)
//
// A LightSample's `weight` is the incident radiance divided by the sample's pdf (solid angle,
// selection included) so a shader adds bsdf(wi = direction) * cos * weight, after a shadow ray
// trace_occluded(origin, direction, distance * (1 - 1e-4)). For punctual lights pdf = 0 (delta).
#pragma once
#include "scene.glsl"

#ifndef SCENE_HAS_PUNCTUAL_LIGHTS
#define SCENE_HAS_PUNCTUAL_LIGHTS 0
#endif
#ifndef SCENE_HAS_EMISSIVE_TRIANGLES
#define SCENE_HAS_EMISSIVE_TRIANGLES 0
#endif

#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u

struct LightSample {
    vec3 direction;   // unit, from p towards the light
    float distance;   // to the light point (1e30 for directional)
    vec3 weight;      // radiance / pdf
    float pdf;        // solid angle (0 for punctual lights)
    bool valid;
};

LightSample no_light_sample() {
    return LightSample(vec3(0.0, 1.0, 0.0), 0.0, vec3(0.0), 0.0, false);
}

#if SCENE_HAS_PUNCTUAL_LIGHTS
struct PunctualLight {
    vec4 position_type;    // anchor-space position (scene.glsl render_shift), type (uint bits)
    vec4 direction_range;  // direction the light points, range (0: infinite)
    vec4 intensity;        // colour * intensity
    vec4 cone;             // cos(outer), 1 / (cos(inner) - cos(outer))
};
layout(std430, binding = RAYVR_PUNCTUAL_LIGHT_SSBO) readonly buffer PunctualLights {
    uvec4 punctual_info;   // x: count
    PunctualLight punctual_lights[];
};

uint punctual_light_count() { return punctual_info.x; }

LightSample eval_punctual_light(uint i, vec3 p) {
    PunctualLight L = punctual_lights[i];
    LightSample s;
    s.pdf = 0.0;
    s.valid = true;
    uint type = floatBitsToUint(L.position_type.w);
    if (type == LIGHT_DIRECTIONAL) {
        s.direction = -L.direction_range.xyz;
        s.distance = 1e30;
        s.weight = L.intensity.rgb;
        return s;
    }
    vec3 to = (L.position_type.xyz + render_shift()) - p;
    float d2 = max(dot(to, to), 1e-12);
    s.distance = sqrt(d2);
    s.direction = to / s.distance;
    float att = 1.0 / d2;
    float range = L.direction_range.w;
    if (range > 0.0) {   // glTF's recommended smooth window
        float r = s.distance / range;
        float window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
        att *= window * window;
    }
    if (type == LIGHT_SPOT) {
        float cd = dot(L.direction_range.xyz, -s.direction);
        float k = clamp((cd - L.cone.x) * L.cone.y, 0.0, 1.0);
        att *= k * k;
    }
    s.weight = L.intensity.rgb * att;
    s.valid = att > 0.0;
    return s;
}
#endif

#if SCENE_HAS_EMISSIVE_TRIANGLES
struct EmissiveTriangle {
    uvec4 ids;        // instance, mesh-local triangle, material
    vec4 cdf_power;   // inclusive CDF, power / total, world area
};
layout(std430, binding = RAYVR_EMISSIVE_TRIANGLE_SSBO) readonly buffer EmissiveTriangles {
    vec4 emissive_info;   // x: count (uint bits), y: total power
    vec4 emissive_info2;
    EmissiveTriangle emissive_triangles[];
};

uint emissive_triangle_count() { return floatBitsToUint(emissive_info.x); }

float emissive_strategy_probability() {
#if SCENE_HAS_PUNCTUAL_LIGHTS
    return punctual_light_count() > 0u ? 0.5 : 1.0;
#else
    return 1.0;
#endif
}

// Render-space vertices of scene triangle tri placed by instance inst.
void emissive_vertices(uint inst, uint tri, out vec3 a, out vec3 b, out vec3 c) {
    a = instance_point_to_render(inst, scene_vertices[scene_indices[3u * tri]].position_u.xyz);
    b = instance_point_to_render(inst, scene_vertices[scene_indices[3u * tri + 1u]].position_u.xyz);
    c = instance_point_to_render(inst, scene_vertices[scene_indices[3u * tri + 2u]].position_u.xyz);
}

uint emissive_find(float u) {   // first entry whose CDF exceeds u
    uint lo = 0u, hi = emissive_triangle_count() - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        if (emissive_triangles[mid].cdf_power.x <= u) lo = mid + 1u; else hi = mid;
    }
    return lo;
}

LightSample sample_emissive(vec3 p, vec3 u, float p_strategy) {
    LightSample s = no_light_sample();
    uint k = emissive_find(u.x);
    EmissiveTriangle e = emissive_triangles[k];
    uint inst = e.ids.x;
    uint tri = scene_triangle(inst, e.ids.y);
    vec3 a, b, c;
    emissive_vertices(inst, tri, a, b, c);
    float su = sqrt(u.y);
    vec2 bary = vec2(1.0 - su, u.z * su);   // weights of b and c: uniform over the triangle
    vec3 q = a + bary.x * (b - a) + bary.y * (c - a);
    vec3 cr = cross(b - a, c - a);
    float area = 0.5 * length(cr);
    if (area <= 0.0) return s;
    vec3 nl = cr / (2.0 * area);
    vec3 to = q - p;
    float d2 = dot(to, to);
    if (d2 <= 0.0) return s;
    s.distance = sqrt(d2);
    s.direction = to / s.distance;
    float cos_l = dot(nl, -s.direction);
    MaterialParams m = material_params(e.ids.z, triangle_uv(tri, bary));
    if (cos_l <= 0.0 && !m.double_sided) return s;
    float pdf = p_strategy * e.cdf_power.y / area * d2 / max(abs(cos_l), 1e-8);
    s.pdf = pdf;
    s.weight = m.emissive / pdf;
    s.valid = pdf > 0.0;
    return s;
}

float emissive_light_pdf(SurfacePoint q, uint instance, vec3 p) {
    vec3 a, b, c;
    emissive_vertices(instance, q.triangle, a, b, c);
    float area = 0.5 * length(cross(b - a, c - a));
    float total = emissive_info.y;
    if (area <= 0.0 || total <= 0.0) return 0.0;
    float power = area * luminance(scene_materials[q.material].emission_cutoff.rgb);
    vec3 to = q.position - p;
    float d2 = dot(to, to);
    float cos_l = abs(dot(q.geometric_normal, normalize(to)));
    return emissive_strategy_probability() * (power / total) / area * d2 / max(cos_l, 1e-8);
}
#endif

// Radiance arriving from direction `dir` (render space, unit) from the scene's environment, for
// rays that leave the scene. (Being rewritten with the environment light: the signature stays.)
vec3 environment_radiance(vec3 dir) { return vec3(0.0); }

LightSample sample_light(vec3 p, vec3 u) {
    LightSample s = no_light_sample();
#if SCENE_HAS_PUNCTUAL_LIGHTS && SCENE_HAS_EMISSIVE_TRIANGLES
    float pe = emissive_strategy_probability();
    if (u.x < pe) return sample_emissive(p, vec3(u.x / pe, u.yz), pe);
    u.x = (u.x - pe) / (1.0 - pe);
    float pp = 1.0 - pe;
#elif SCENE_HAS_EMISSIVE_TRIANGLES
    return sample_emissive(p, u, 1.0);
#else
    float pp = 1.0;
#endif
#if SCENE_HAS_PUNCTUAL_LIGHTS
    uint n = punctual_light_count();
    if (n == 0u) return s;
    uint i = min(uint(u.x * float(n)), n - 1u);
    s = eval_punctual_light(i, p);
    s.weight *= float(n) / pp;
#endif
    return s;
}
