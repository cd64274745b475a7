// The lights of rayvr.scene.GpuScene, all in one table sampled by power (rayvr/scene/light_table.py:
// an alias table, O(1) per sample): KHR_lights_punctual lights (point, spot, directional), emissive
// triangles, and the environment (a uniform radiance or an equirectangular map, importance-sampled
// by luminance x sin(theta) through a marginal and per-row conditional CDF).
//
//   LightSample sample_light(vec3 p, vec3 u)   one light sample for shading point p, u in [0,1)^3
//   vec3  environment_radiance(vec3 dir)       radiance of rays that leave the scene along dir
//   float environment_light_pdf(vec3 dir)      solid-angle pdf with which sample_light picks dir (MIS)
//   float emissive_light_pdf(SurfacePoint q, uint instance, vec3 p)   the same for point q on an
//         emissive triangle seen from p
//   LightSample eval_punctual_light(uint i, vec3 p)   light i alone, weight without selection
//   LightSample sample_light_id(vec3 p, vec3 u, out uvec2 id)   sample_light, and the sample's
//         identity: which light and which point of it (see "Light identities" below)
//   LightSample light_id_eval(uvec2 id, vec3 p)   that same point of that light seen from another p
//
// Which punctual light: the table draws the punctual lights' group by their share of the power;
// in a scene of at most LOCAL_PUNCTUAL_MAX of them the light within the group is then drawn by its
// unshadowed irradiance at p (distance falloff, range window, spot cone), so a point outside a
// spot's cone never spends its sample on the spot (tauray/test.glb: a sun and a 10-degree spot,
// the sun-lit walls had half their pixels black in every frame). Unbiased: the weight divides by
// that probability, and a light whose irradiance at p is 0 adds nothing either way.
//
// A LightSample's `weight` is the incident radiance divided by the sample's pdf (solid angle,
// selection included) so a shader adds bsdf(wi = direction) * cos * weight, after a shadow ray
// (shadow_ray: from the offset origin to the sampled point). For punctual lights pdf = 0 (delta).
#pragma once
#include "scene.glsl"
#include "color.glsl"
#include "octahedral.glsl"
#include "light_records.glsl"   // PunctualLight, LightEntry

#ifndef SCENE_HAS_PUNCTUAL_LIGHTS
#define SCENE_HAS_PUNCTUAL_LIGHTS 0
#endif
#ifndef SCENE_HAS_EMISSIVE_TRIANGLES
#define SCENE_HAS_EMISSIVE_TRIANGLES 0
#endif
#ifndef SCENE_HAS_ENVIRONMENT
#define SCENE_HAS_ENVIRONMENT 0
#endif
#ifndef SCENE_HAS_ENVIRONMENT_MAP
#define SCENE_HAS_ENVIRONMENT_MAP 0
#endif
#define SCENE_HAS_LIGHTS (SCENE_HAS_PUNCTUAL_LIGHTS || SCENE_HAS_EMISSIVE_TRIANGLES || SCENE_HAS_ENVIRONMENT)

#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u
#define LIGHT_KIND_PUNCTUAL 0u
#define LIGHT_KIND_EMISSIVE 1u
#define LIGHT_KIND_ENVIRONMENT 2u

struct LightSample {
    vec3 direction;   // unit, from p towards the light
    float distance;   // to the light point (1e30 for directional lights and the environment)
    vec3 weight;      // radiance / pdf
    float pdf;        // solid angle (0 for punctual lights)
    bool valid;
};

LightSample no_light_sample() {
    return LightSample(vec3(0.0, 1.0, 0.0), 0.0, vec3(0.0), 0.0, false);
}

// ---- light identities ---------------------------------------------------------------------------
// A sample's identity names the light and the point of it, so that the same sample can be
// evaluated at another shading point (ReSTIR's reuse, passes/restir_di): x = kind << 30 | index
// (the punctual light; the emissive triangle's entry; 0 for the environment), y = the point
// (an emissive triangle's two random numbers as unorm16, from which its barycentrics follow; the
// environment's direction as octahedral snorm16; 0 for a punctual light). sample_light_id draws
// those points from the rounded numbers, so an identity evaluates to exactly the point drawn.
const uint LIGHT_ID_NONE = 0xFFFFFFFFu;   // kind 3: no sample
uvec2 light_id(uint kind, uint index, uint point) { return uvec2((kind << 30u) | index, point); }
uint light_id_kind(uvec2 id) { return id.x >> 30u; }
uint light_id_index(uvec2 id) { return id.x & 0x3FFFFFFFu; }

// One step of a single-pass weighted choice (a reservoir of one): a candidate of weight w > 0
// joins `total` and replaces the pick so far with probability w / total (true), r in [0, 1)
// rescaled to stay uniform for the steps after it.
bool reservoir_take(float w, inout float total, inout float r) {
    total += w;
    float q = w / total;
    bool take = r < q;
    r = min(take ? r / q : (r - q) / (1.0 - q), 0.99999994);
    return take;
}

// The shadow ray of light sample ls taken at p, from `origin` (p moved off its surface:
// offset_ray_origin): aimed at the sampled point itself and stopping 1e-4 of the way short of it.
// Aiming from p instead (ls.direction, ls.distance) moves the ray's end into the emitter by the
// origin's offset: a lamp 0.4 m above a floor 3 m from the render origin hid itself (the offset,
// 6e-5 m, outgrew the 4e-5 m margin).
void shadow_ray(vec3 p, vec3 origin, LightSample ls, out vec3 dir, out float tmax) {
    dir = ls.direction;
    tmax = ls.distance * (1.0 - 1e-4);
    if (ls.distance >= 1e29) return;   // directional light, environment: no end point
    vec3 to = p + ls.direction * ls.distance - origin;
    float d = length(to);
    if (!(d > 0.0)) return;
    dir = to / d;
    tmax = d * (1.0 - 1e-4);
}

#if SCENE_HAS_LIGHTS
layout(std430, binding = RAYVR_LIGHT_TABLE_SSBO) readonly buffer LightTable {
    vec4 light_table_info;   // x: count (uint bits), y: total power, z: environment probability, w: 1 / total
    LightEntry light_entries[];
};

uint light_count() { return floatBitsToUint(light_table_info.x); }
#endif

// ---- punctual lights ----------------------------------------------------------------------------
#if SCENE_HAS_PUNCTUAL_LIGHTS
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
    float d2 = max(dot(to, to), 1e-30);
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

#ifndef LOCAL_PUNCTUAL_MAX
#define LOCAL_PUNCTUAL_MAX 8
#endif

// The weight the local choices give punctual light sample c: its unshadowed irradiance (luminance).
float punctual_local_weight(LightSample c) { return c.valid ? luminance(c.weight) : 0.0; }

// sample_punctual_local's choice: the pick, its weight and index and the n lights' summed weight.
LightSample punctual_local_pick(vec3 p, uint n, float r, out float total, out float w_pick, out uint index) {
    LightSample pick = no_light_sample();
    total = 0.0;
    w_pick = 0.0;
    index = 0u;
    for (uint i = 0u; i < n; ++i) {
        LightSample c = eval_punctual_light(i, p);
        float w = punctual_local_weight(c);
        if (!(w > 0.0)) continue;
        if (reservoir_take(w, total, r)) {
            pick = c;
            w_pick = w;
            index = i;
        }
    }
    return pick;
}

// One of the n (2..LOCAL_PUNCTUAL_MAX) punctual lights, drawn by its unshadowed irradiance at p
// with r in [0, 1); `share`: the probability with which the table drew the punctual group. One
// pass, no array (a small shader: llvmpipe compiles every pass that lights): light i replaces the
// pick so far with probability w_i / (w_0 + ... + w_i), r rescaled to stay uniform.
LightSample sample_punctual_local(vec3 p, uint n, float r, float share, out uint index) {
    float total, w_pick;
    LightSample pick = punctual_local_pick(p, n, r, total, w_pick, index);
    if (!(w_pick > 0.0) || !(share > 0.0)) return no_light_sample();
    pick.weight *= total / (w_pick * share);
    return pick;
}

// The summed unshadowed irradiance (luminance) the n punctual lights give p: what the spatial
// selection weighs the punctual lights by.
float punctual_local_total(vec3 p, uint n) {
    float total = 0.0;
    for (uint i = 0u; i < n; ++i) {
        float w = punctual_local_weight(eval_punctual_light(i, p));
        if (w > 0.0) total += w;
    }
    return total;
}
#endif

// ---- emissive triangles ---------------------------------------------------------------------------
#if SCENE_HAS_EMISSIVE_TRIANGLES
#ifndef LIGHTS_SPATIAL
#define LIGHTS_SPATIAL 0   // GpuScene.defines(): Scene.light_selection "spatial" (the clusters below)
#endif
#if LIGHTS_SPATIAL
#define EMISSIVE_CLUSTERS_MAX 16   // light_table.EMISSIVE_CLUSTERS_MAX
struct EmissiveCluster {   // one instance's emissive triangles (light_table.pack_clusters)
    vec4 sphere;      // anchor-space centre of the instance's emissive vertices, world radius
    uvec4 ids;        // instance, first entry, entry count, power (float bits)
};
struct EmissiveTriangle {
    uvec4 ids;        // instance, mesh-local triangle, material, alias entry (within its cluster)
    vec4 select;      // x: alias threshold (within its cluster)
};
layout(std430, binding = RAYVR_EMISSIVE_TRIANGLE_SSBO) readonly buffer EmissiveTriangles {
    uvec4 emissive_info;   // x: clusters (0: the light table alone draws)
    EmissiveCluster emissive_clusters[EMISSIVE_CLUSTERS_MAX];
    EmissiveTriangle emissive_triangles[];
};

// The irradiance (luminance) cluster c may give p: power / (pi max(d^2, r^2)), as if all of it
// left a disc facing p from the cluster's centre (capped inside its bounding sphere).
float emissive_cluster_estimate(uint c, vec3 p) {
    vec4 sphere = emissive_clusters[c].sphere;
    vec3 to = sphere.xyz + render_shift() - p;
    return uintBitsToFloat(emissive_clusters[c].ids.w) / (RAYVR_PI * max(dot(to, to), sphere.w * sphere.w));
}
#else
struct EmissiveTriangle {
    uvec4 ids;        // instance, mesh-local triangle, material
};
layout(std430, binding = RAYVR_EMISSIVE_TRIANGLE_SSBO) readonly buffer EmissiveTriangles {
    EmissiveTriangle emissive_triangles[];
};
#endif

// Render-space vertices of scene triangle tri placed by instance inst.
void emissive_vertices(uint inst, uint tri, out vec3 a, out vec3 b, out vec3 c) {
    a = instance_point_to_render(inst, scene_vertices[scene_indices[3u * tri]].position_u.xyz);
    b = instance_point_to_render(inst, scene_vertices[scene_indices[3u * tri + 1u]].position_u.xyz);
    c = instance_point_to_render(inst, scene_vertices[scene_indices[3u * tri + 2u]].position_u.xyz);
}

// Selection probability per unit area of a point on an emissive triangle of material m: its power
// pi L A (x 2 double-sided) times `per_power`, the probability per unit power of its group (the
// table's 1 / total, or a cluster's share / its power), over its area A, which cancels
// (light_table.py).
float emissive_area_pdf(uint m, float per_power) {
    float sides = scene_materials[m].flags.z != 0u ? 2.0 : 1.0;
    return RAYVR_PI * sides * luminance(scene_materials[m].emission_cutoff.rgb) * per_power;
}

// The point of emissive triangle entry k that random numbers u name, seen from p: the LightSample
// (pdf: drawn with probability `per_power` per unit power), and `radiance_g` = its radiance x
// |cos_l| / d^2, what it gives p per unit area (however it was drawn).
LightSample emissive_point(uint k, vec3 p, vec2 u, float per_power, out vec3 radiance_g) {
    LightSample s = no_light_sample();
    radiance_g = vec3(0.0);
    EmissiveTriangle e = emissive_triangles[k];
    uint inst = e.ids.x;
    uint tri = scene_triangle(inst, e.ids.y);
    vec3 a, b, c;
    emissive_vertices(inst, tri, a, b, c);
    float su = sqrt(u.x);
    vec2 bary = vec2(1.0 - su, u.y * su);   // weights of b and c: uniform over the triangle
    vec3 q = a + bary.x * (b - a) + bary.y * (c - a);
    vec3 cr = cross(b - a, c - a);
    float cl = length(cr);
    if (!(cl > 0.0)) return s;
    vec3 nl = cr / cl;
    vec3 to = q - p;
    float d2 = dot(to, to);
    if (!(d2 > 0.0)) return s;
    s.distance = sqrt(d2);
    s.direction = to / s.distance;
    float cos_l = dot(nl, -s.direction);
    MaterialParams m = material_params(e.ids.z, triangle_uv(tri, bary));
    if (cos_l <= 0.0 && !m.double_sided) return s;   // the back of a single-sided emitter is dark
    vec3 emitted = m.emissive;
#if SCENE_HAS_ALPHA_BLEND
    // a BLEND emitter is there for a ray with probability alpha (scene.glsl): its expected light
    if (m.alpha_mode == ALPHA_MODE_BLEND) emitted *= m.alpha;
#endif
    s.pdf = emissive_area_pdf(e.ids.z, per_power) * d2 / max(abs(cos_l), 1e-12);
    s.weight = emitted / s.pdf;
    s.valid = s.pdf > 0.0;
    radiance_g = emitted * (abs(cos_l) / d2);
    return s;
}

LightSample sample_emissive(uint k, vec3 p, vec2 u, float per_power) {
    vec3 radiance_g;
    return emissive_point(k, p, u, per_power, radiance_g);
}

#if LIGHTS_SPATIAL
// Spatial selection (light_table.py) when the buffer has clusters and the punctual lights are few.
bool lights_spatial() {
#if SCENE_HAS_PUNCTUAL_LIGHTS
    if (punctual_light_count() > uint(LOCAL_PUNCTUAL_MAX)) return false;
#endif
    return emissive_info.x > 0u;
}

// The punctual lights' irradiance estimate at p (0 without them), the spatial selection's weight.
float punctual_estimate(vec3 p) {
#if SCENE_HAS_PUNCTUAL_LIGHTS
    return punctual_local_total(p, punctual_light_count());
#else
    return 0.0;
#endif
}

// Probability per unit power with which the spatial selection draws `instance`'s cluster at p.
float emissive_spatial_per_power(uint instance, vec3 p) {
    float w_e = 0.0, w_c = 0.0, power = 1.0;
    for (uint c = 0u; c < emissive_info.x; ++c) {
        float w = emissive_cluster_estimate(c, p);
        w_e += w;
        if (emissive_clusters[c].ids.x == instance) {
            w_c = w;
            power = uintBitsToFloat(emissive_clusters[c].ids.w);
        }
    }
    return (1.0 - light_table_info.z) * w_c / ((punctual_estimate(p) + w_e) * power);
}
#endif

// Probability per unit power with which sample_light draws `instance`'s emissive triangles at p.
float emissive_per_power(uint instance, vec3 p) {
#if LIGHTS_SPATIAL
    if (lights_spatial()) return emissive_spatial_per_power(instance, p);
#endif
    return light_table_info.w;
}

float emissive_light_pdf(SurfacePoint q, uint instance, vec3 p) {
    vec3 to = q.position - p;
    float d2 = dot(to, to);
    float cos_l = abs(dot(q.geometric_normal, to)) * inversesqrt(max(d2, 1e-30));
    return emissive_area_pdf(q.material, emissive_per_power(instance, p)) * d2 / max(cos_l, 1e-12);
}
#endif

// ---- the environment ------------------------------------------------------------------------------
#if SCENE_HAS_ENVIRONMENT
layout(std430, binding = RAYVR_ENVIRONMENT_SSBO) readonly buffer EnvironmentData {
    vec4 env_color;    // rgb: uniform radiance, or the map's multiplier
    vec4 env_info;     // x: width, y: height (uint bits), z: mean of luminance x sin(theta) over the texels
    float env_cdf[];   // the map: marginal CDF over rows (height), then per row a CDF over columns (width)
};
#if SCENE_HAS_ENVIRONMENT_MAP
uniform sampler2D scene_environment;   // bound by GpuScene.bind() at RAYVR_ENVIRONMENT_TEXTURE_UNIT

// (u, v) of the equirectangular map for a direction: u = 0.5 looks down -Z, v = 0 up (+Y).
vec2 environment_uv(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) * (0.5 / RAYVR_PI), acos(clamp(d.y, -1.0, 1.0)) / RAYVR_PI);
}

vec3 environment_direction(vec2 uv) {
    float phi = (uv.x - 0.5) * 2.0 * RAYVR_PI, theta = uv.y * RAYVR_PI;
    float st = sin(theta);
    return vec3(st * sin(phi), cos(theta), -st * cos(phi));
}

uint env_find(uint first, uint count, float u) {   // first entry of cdf[first..first+count) above u
    uint lo = 0u, hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        if (env_cdf[first + mid] <= u) lo = mid + 1u; else hi = mid;
    }
    return lo;
}

// Solid-angle pdf of the map's importance sampling for direction d.
float environment_map_pdf(vec3 d) {
    uint w = floatBitsToUint(env_info.x), h = floatBitsToUint(env_info.y);
    vec2 uv = environment_uv(d);
    ivec2 t = ivec2(min(uint(uv.x * float(w)), w - 1u), min(uint(uv.y * float(h)), h - 1u));
    float row_sin = sin((float(t.y) + 0.5) / float(h) * RAYVR_PI);
    float density = luminance(texelFetch(scene_environment, ivec2(t.x, t.y), 0).rgb) * row_sin / env_info.z;
    float st = sqrt(max(1.0 - d.y * d.y, 0.0));
    return density / max(2.0 * RAYVR_PI * RAYVR_PI * st, 1e-12);
}
#endif

vec3 environment_radiance(vec3 dir) {
#if SCENE_HAS_ENVIRONMENT_MAP
    return env_color.rgb * textureLod(scene_environment, environment_uv(dir), 0.0).rgb;
#else
    return env_color.rgb;
#endif
}

// The environment's own direction pdf (uniform over the sphere, or the map's).
float environment_direction_pdf(vec3 dir) {
#if SCENE_HAS_ENVIRONMENT_MAP
    return environment_map_pdf(dir);
#else
    return 1.0 / (4.0 * RAYVR_PI);
#endif
}

float environment_light_pdf(vec3 dir) { return light_table_info.z * environment_direction_pdf(dir); }

// The environment's light from unit direction dir, as sample_light draws it.
LightSample environment_toward(vec3 dir) {
    LightSample s;
    s.direction = dir;
    s.distance = 1e30;
    s.pdf = environment_light_pdf(dir);
    s.weight = environment_radiance(dir) / max(s.pdf, 1e-30);
    s.valid = s.pdf > 0.0;
    return s;
}

// The direction random numbers u draw from the environment (importance sampled).
vec3 sample_environment_direction(vec2 u) {
    vec3 direction;
#if SCENE_HAS_ENVIRONMENT_MAP
    uint w = floatBitsToUint(env_info.x), h = floatBitsToUint(env_info.y);
    uint row = env_find(0u, h, u.y);
    float r0 = row > 0u ? env_cdf[row - 1u] : 0.0;
    float fy = (u.y - r0) / max(env_cdf[row] - r0, 1e-30);
    uint first = h + row * w;
    uint col = env_find(first, w, u.x);
    float c0 = col > 0u ? env_cdf[first + col - 1u] : 0.0;
    float fx = (u.x - c0) / max(env_cdf[first + col] - c0, 1e-30);
    direction = environment_direction(vec2((float(col) + clamp(fx, 0.0, 1.0)) / float(w),
                                           (float(row) + clamp(fy, 0.0, 1.0)) / float(h)));
#else
    float z = 1.0 - 2.0 * u.x, r = sqrt(max(0.0, 1.0 - z * z)), phi = 2.0 * RAYVR_PI * u.y;
    direction = vec3(r * cos(phi), z, r * sin(phi));
#endif
    return direction;
}
#else
vec3 environment_radiance(vec3 dir) { return vec3(0.0); }
float environment_light_pdf(vec3 dir) { return 0.0; }
#endif

// ---- one sample of all of them ------------------------------------------------------------------
// `named`: the sample's point is rounded to what its identity `id` holds (light identities above),
// so that light_id_eval(id, p) gives this sample again; sample_light keeps the exact point.
#if SCENE_HAS_ENVIRONMENT
LightSample environment_sample(vec2 u, bool named, out uvec2 id) {
    vec3 d = sample_environment_direction(u);
    uint bits = oct_pack_snorm16(d);
    id = light_id(LIGHT_KIND_ENVIRONMENT, 0u, bits);
    return environment_toward(named ? oct_unpack_snorm16(bits) : d);
}
#endif

#if SCENE_HAS_EMISSIVE_TRIANGLES
LightSample emissive_sample(uint k, vec3 p, vec2 u, float per_power, bool named, out uvec2 id) {
    uint bits = packUnorm2x16(u);
    id = light_id(LIGHT_KIND_EMISSIVE, k, bits);
    return sample_emissive(k, p, named ? unpackUnorm2x16(bits) : u, per_power);
}
#endif

#if SCENE_HAS_EMISSIVE_TRIANGLES && LIGHTS_SPATIAL
// Spatial selection (light_table.py): the environment by its share of the power; below it the
// punctual lights (drawn among themselves as sample_punctual_local does) and each emissive
// cluster, by their irradiance estimates at p, in one pass over the candidates (each replaces the
// pick so far with probability w / running sum, x rescaled to stay uniform); within a cluster a
// triangle by its power (the cluster's alias table). u.x makes the choices, u.yz the point.
LightSample sample_light_spatial(vec3 p, vec3 u, bool named, out uvec2 id) {
    id = uvec2(LIGHT_ID_NONE, 0u);
    float x = u.x;
    float rest = 1.0 - light_table_info.z;   // what the environment leaves
#if SCENE_HAS_ENVIRONMENT
    if (x < light_table_info.z) return environment_sample(u.yz, named, id);
    x = min((x - light_table_info.z) / rest, 0.99999994);
#endif
    float sum = 0.0, w_pick = 0.0;
    uint index = 0u;
    LightSample pick = no_light_sample();
#if SCENE_HAS_PUNCTUAL_LIGHTS
    pick = punctual_local_pick(p, punctual_light_count(), u.y, sum, w_pick, index);
#endif
    float w_chosen = sum;   // the punctual lights' estimate while they are the pick
    uint chosen = 0xFFFFFFFFu;
    for (uint c = 0u; c < emissive_info.x; ++c) {
        float w = emissive_cluster_estimate(c, p);
        if (!(w > 0.0)) continue;
        if (reservoir_take(w, sum, x)) {
            chosen = c;
            w_chosen = w;
        }
    }
    if (chosen == 0xFFFFFFFFu) {
        if (!(w_pick > 0.0)) return no_light_sample();
        pick.weight *= sum / (w_pick * rest);   // 1 / (rest * w_pick / sum)
        id = light_id(LIGHT_KIND_PUNCTUAL, index, 0u);
        return pick;
    }
    uvec4 k = emissive_clusters[chosen].ids;
    float y = x * float(k.z);
    uint i = min(uint(y), k.z - 1u);
    uint j = k.y + i;
    if (y - float(i) >= emissive_triangles[j].select.x) j = emissive_triangles[j].ids.w;
    return emissive_sample(j, p, u.yz, rest * w_chosen / (sum * uintBitsToFloat(k.w)), named, id);
}
#endif

LightSample sample_light_named(vec3 p, vec3 u, bool named, out uvec2 id) {
    id = uvec2(LIGHT_ID_NONE, 0u);
#if SCENE_HAS_LIGHTS
#if SCENE_HAS_EMISSIVE_TRIANGLES && LIGHTS_SPATIAL
    if (lights_spatial()) return sample_light_spatial(p, u, named, id);
#endif
    uint n = light_count();
    if (n == 0u) return no_light_sample();
    float x = u.x * float(n);
    uint k = min(uint(x), n - 1u);
    // entry k, or its alias; then one load of the chosen entry (reassigning a LightEntry read from
    // the buffer has given a selection probability that was not the drawn light's: 1.3-1.5x too
    // bright under 100-10,000 point lights of unequal power)
    uint j = x - float(k) < light_entries[k].select.x ? k : light_entries[k].ids.z;
    LightEntry e = light_entries[j];
    float p_select = e.select.y;
#if SCENE_HAS_PUNCTUAL_LIGHTS
    if (e.ids.x == LIGHT_KIND_PUNCTUAL) {
        uint np = punctual_light_count();
        uint index = e.ids.y;
        LightSample s;
        if (np > 1u && np <= uint(LOCAL_PUNCTUAL_MAX)) {
            s = sample_punctual_local(p, np, u.y, e.select.z, index);
        } else {
            s = eval_punctual_light(index, p);
            s.weight /= p_select;
        }
        if (s.valid) id = light_id(LIGHT_KIND_PUNCTUAL, index, 0u);
        return s;
    }
#endif
#if SCENE_HAS_EMISSIVE_TRIANGLES
    if (e.ids.x == LIGHT_KIND_EMISSIVE) return emissive_sample(e.ids.y, p, u.yz, light_table_info.w, named, id);
#endif
#if SCENE_HAS_ENVIRONMENT
    if (e.ids.x == LIGHT_KIND_ENVIRONMENT) return environment_sample(u.yz, named, id);
#endif
#endif
    return no_light_sample();
}

LightSample sample_light(vec3 p, vec3 u) {
    uvec2 id;
    return sample_light_named(p, u, false, id);
}

LightSample sample_light_id(vec3 p, vec3 u, out uvec2 id) { return sample_light_named(p, u, true, id); }

// The light sample that identity `id` names, seen from p: direction, distance and `pdf` as
// sample_light draws it there (solid angle; 0 for a punctual light), and `weight` its radiance
// times the geometry factor of its light's measure (an emissive point's |cos_l| / d^2 per unit
// area; a punctual light's falloff, range and cone; 1 for an environment direction): what a
// contribution weight in that measure multiplies. `valid`: it gives p any light.
LightSample light_id_eval(uvec2 id, vec3 p) {
#if SCENE_HAS_LIGHTS
    uint kind = light_id_kind(id);
#if SCENE_HAS_PUNCTUAL_LIGHTS
    if (kind == LIGHT_KIND_PUNCTUAL) return eval_punctual_light(light_id_index(id), p);
#endif
#if SCENE_HAS_EMISSIVE_TRIANGLES
    if (kind == LIGHT_KIND_EMISSIVE) {
        uint k = light_id_index(id);
        vec3 radiance_g;
        LightSample s = emissive_point(k, p, unpackUnorm2x16(id.y), emissive_per_power(emissive_triangles[k].ids.x, p),
                                       radiance_g);
        s.weight = radiance_g;
        s.valid = max3(radiance_g) > 0.0;
        return s;
    }
#endif
#if SCENE_HAS_ENVIRONMENT
    if (kind == LIGHT_KIND_ENVIRONMENT) {
        LightSample s = environment_toward(oct_unpack_snorm16(id.y));
        s.weight = environment_radiance(s.direction);
        s.valid = max3(s.weight) > 0.0;
        return s;
    }
#endif
#endif
    return no_light_sample();
}
