// The GPU scene (rayvr.scene.GpuScene): buffers, vertex pulling for raster, surfaces and materials.
//
// Spaces: vertices are object space; InstanceData holds object -> anchor space (world minus the
// anchor, where the instances were last uploaded) as three rows of a 3x4 matrix, and the
// inverse; render space (world minus the frame's origin) = anchor space + scene_shift
// (rayvr/scene/gpu_frame.py). All results are render space.
//
// Raster: GpuScene.draw(program, instances_per_draw) issues ONE glMultiDrawArraysIndirect over
// all instances, with no index buffer: command i draws instance i's mesh as 3*T vertices with
// first = the mesh's first index slot, so gl_VertexID is a position in scene_indices[] (and
// gl_VertexID / 3 the scene-wide triangle), instanceCount = instances_per_draw and
// baseInstance = i * instances_per_draw. The vertex shader declares
//     in uint rayvr_instance;        // per-instance attribute fed by GpuScene.draw
// and calls scene_raster_vertex(rayvr_instance, gl_VertexID). With layered stereo
// (instances_per_draw = views) gl_InstanceID is the view (layer); with GL_OVR_multiview2
// (instances_per_draw = 1) gl_ViewID_OVR is.
//
// Feature #defines (GpuScene.defines(), 0 or 1): SCENE_HAS_TEXTURES, SCENE_HAS_NORMAL_MAPS,
// SCENE_HAS_ALPHA_MASK, SCENE_HAS_ALPHA_BLEND, SCENE_HAS_TRANSMISSION, SCENE_HAS_PUNCTUAL_LIGHTS,
// SCENE_HAS_EMISSIVE_TRIANGLES, SCENE_HAS_INSTANCING. Define SCENE_MATERIAL_GRADIENTS 1 in a
// fragment shader to sample material textures with mip selection from the screen-space gradients
// of uv it sets in `material_uv_dx` / `material_uv_dy` first thing in main(): implicit derivatives
// are undefined in the non-uniform control flow of material_params_at (a texture's `if`; a quad
// may straddle two materials), and llvmpipe's came out as a lattice of wrong mip levels, one pixel
// of each 2x2 quad. Ray passes pass a ray cone's footprint instead (surface_at_cone,
// material_params_at: Akenine-Moeller et al., "Texture Level of Detail Strategies for Real-Time
// Ray Tracing", Ray Tracing Gems ch. 20), or read level 0.
#pragma once
#include "color.glsl"
#include "sampling.glsl"

#ifndef RAYVR_PI
#define RAYVR_PI 3.14159265358979323846
#endif

#ifndef SCENE_HAS_TEXTURES
#define SCENE_HAS_TEXTURES 0
#endif
#ifndef SCENE_HAS_NORMAL_MAPS
#define SCENE_HAS_NORMAL_MAPS 0
#endif
#ifndef SCENE_HAS_ALPHA_MASK
#define SCENE_HAS_ALPHA_MASK 0
#endif
#ifndef SCENE_HAS_ALPHA_BLEND
#define SCENE_HAS_ALPHA_BLEND 0
#endif
#ifndef SCENE_HAS_TRANSMISSION
#define SCENE_HAS_TRANSMISSION 0
#endif
#ifndef SCENE_MATERIAL_GRADIENTS
#define SCENE_MATERIAL_GRADIENTS 0
#endif
#if SCENE_MATERIAL_GRADIENTS
vec2 material_uv_dx, material_uv_dy;   // d uv / d screen x and y, set in uniform control flow
#endif


#define ALPHA_MODE_OPAQUE 0u
#define ALPHA_MODE_MASK 1u
#define ALPHA_MODE_BLEND 2u

#include "scene_records.glsl"   // TEX_* slot ids, InstanceData, MaterialData

struct VertexData {
    vec4 position_u;   // object-space position, uv.x
    vec4 normal_v;     // object-space normal, uv.y
};

layout(std430, binding = RAYVR_VERTEX_SSBO) readonly buffer SceneVertices { VertexData scene_vertices[]; };
layout(std430, binding = RAYVR_INDEX_SSBO) readonly buffer SceneIndices { uint scene_indices[]; };
layout(std430, binding = RAYVR_INSTANCE_SSBO) readonly buffer SceneInstances {
    uvec4 scene_info;      // x: instance count, y: material count
    vec4 scene_shift;      // xyz: anchor - origin, render space = anchor space + shift
    InstanceData scene_instances[];
};
layout(std430, binding = RAYVR_MATERIAL_SSBO) readonly buffer SceneMaterials { MaterialData scene_materials[]; };
layout(std430, binding = RAYVR_TRIANGLE_MATERIAL_SSBO) readonly buffer SceneTriangleMaterials {
    uint scene_triangle_materials[];   // per scene triangle: material id | TRIANGLE_CONVEX_BIT
};
// The whole mesh lies behind this triangle (rayvr.scene.convex_faces): a ray leaving it through
// its front cannot meet the mesh again.
#define TRIANGLE_CONVEX_BIT 0x80000000u
#include "exit_instance.glsl"   // SCENE_NO_INSTANCE

uint triangle_word_material(uint word) { return word & ~TRIANGLE_CONVEX_BIT; }
bool triangle_word_convex(uint word) { return (word & TRIANGLE_CONVEX_BIT) != 0u; }
uint triangle_material(uint tri) { return triangle_word_material(scene_triangle_materials[tri]); }

// SurfacePoint.exit_instance of a surface seen on a triangle of `convex_instance` (its instance
// where the triangle is convex, else SCENE_NO_INSTANCE): only a front face, since rays leave on
// the side seen and only the front has the mesh behind it.
uint exit_instance_seen(uint convex_instance, bool front_face) { return front_face ? convex_instance : SCENE_NO_INSTANCE; }
#if SCENE_HAS_NORMAL_MAPS
layout(std430, binding = RAYVR_TANGENT_SSBO) readonly buffer SceneTangents { vec4 scene_tangents[]; };
#endif
#if SCENE_HAS_TEXTURES
layout(binding = RAYVR_SCENE_TEXTURE_UNIT) uniform sampler2DArray scene_textures;
#endif

uint instance_count() { return scene_info.x; }

vec3 render_shift() { return scene_shift.xyz; }

vec3 instance_point_to_render(uint i, vec3 p) {
    vec4 q = vec4(p, 1.0);
    return vec3(dot(scene_instances[i].to_render[0], q), dot(scene_instances[i].to_render[1], q),
                dot(scene_instances[i].to_render[2], q)) + scene_shift.xyz;
}

vec3 instance_vector_to_render(uint i, vec3 v) {
    return vec3(dot(scene_instances[i].to_render[0].xyz, v), dot(scene_instances[i].to_render[1].xyz, v),
                dot(scene_instances[i].to_render[2].xyz, v));
}

// Normals go by the inverse transpose: n' = transpose(to_object) * n.
vec3 instance_normal_to_render(uint i, vec3 n) {
    return n.x * scene_instances[i].to_object[0].xyz + n.y * scene_instances[i].to_object[1].xyz
         + n.z * scene_instances[i].to_object[2].xyz;
}

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float l2 = dot(v, v);
    return l2 > 1e-30 ? v * inversesqrt(l2) : fallback;
}

uint scene_triangle(uint instance, uint primitive) {
    return scene_instances[instance].info.z + primitive;
}

// ---- materials ------------------------------------------------------------------------------

struct MaterialParams {
    vec3 base_color;
    float alpha;
    float metallic;
    float roughness;
    vec3 emissive;        // emitted radiance (emissive * strength * texture)
    float occlusion;
    float transmission;
    float ior;
    float specular;       // dielectric specular strength (f90), KHR_materials_specular
    vec3 specular_color;  // dielectric F0 tint
    bool volume;          // a volume boundary (KHR_materials_volume thickness > 0), else thin-walled
    vec3 attenuation;     // absorption coefficient inside the volume, per metre (0: clear)
    uint effect;          // rayvr.Effect id
    uint alpha_mode;
    bool double_sided;
};

// Perceptual roughness below which a material's lobes are deltas (a mirror, straight refraction):
// bsdf.glsl's BSDF_DELTA_ROUGHNESS, and what the G-buffer keeps exact through its float16 roughness.
const float MATERIAL_DELTA_ROUGHNESS = 1e-3;

// uv_lod: log2 of a ray's footprint in (untransformed) uv units; UV_LOD_FINEST reads level 0.
#define UV_LOD_FINEST -64.0

#if SCENE_HAS_TEXTURES
bool material_has_texture(uint m, int slot) { return scene_materials[m].tex[2 * slot].w >= 0.0; }

vec4 material_texture(uint m, int slot, vec2 uv, float uv_lod) {
    vec4 r0 = scene_materials[m].tex[2 * slot], r1 = scene_materials[m].tex[2 * slot + 1];
    vec3 st = vec3(dot(r0.xy, uv) + r0.z, dot(r1.xy, uv) + r1.z, r0.w);
#if SCENE_MATERIAL_GRADIENTS   // the slot's transform applied to the gradients too
    return textureGrad(scene_textures, st, vec2(dot(r0.xy, material_uv_dx), dot(r1.xy, material_uv_dx)),
                       vec2(dot(r0.xy, material_uv_dy), dot(r1.xy, material_uv_dy)));
#else
    // footprint in texels: the slot's KHR_texture_transform scales uv areas by |det|
    ivec2 size = textureSize(scene_textures, 0).xy;
    float texel_lod = uv_lod + 0.5 * log2(float(size.x) * float(size.y) * max(abs(r0.x * r1.y - r0.y * r1.x), 1e-30));
    return textureLod(scene_textures, st, max(texel_lod, 0.0));
#endif
}
#endif

// Material m's factors as its table entry holds them, before any texture.
MaterialParams material_factors(uint m) {
    MaterialData d = scene_materials[m];
    MaterialParams p;
    p.base_color = d.base_color.rgb;
    p.alpha = d.base_color.a;
    p.metallic = d.pbr.x;
    p.roughness = d.pbr.y;
    p.emissive = d.emission_cutoff.rgb;
    p.occlusion = 1.0;
    p.transmission = 0.0;
    p.ior = d.pbr.w;
    p.specular = d.specular.a;
    p.specular_color = d.specular.rgb;
    p.volume = false;
    p.attenuation = vec3(0.0);
    p.effect = d.flags.x;
    p.alpha_mode = d.flags.y;
    p.double_sided = d.flags.z != 0u;
#if SCENE_HAS_TRANSMISSION
    p.transmission = d.pbr.z;
    p.volume = d.flags.w != 0u;
    // Beer-Lambert: white light turns attenuation colour after the attenuation distance
    p.attenuation = -log(max(d.volume.rgb, vec3(1e-30))) / d.volume.a;
#endif
    return p;
}

// The material's parameters at uv, textures read for a footprint of 2^uv_lod uv units.
MaterialParams material_params_at(uint m, vec2 uv, float uv_lod) {
    MaterialParams p = material_factors(m);
#if SCENE_HAS_TEXTURES
    MaterialData d = scene_materials[m];
    if (d.tex[2 * TEX_BASE_COLOR].w >= 0.0) {
        vec4 t = material_texture(m, TEX_BASE_COLOR, uv, uv_lod);
        p.base_color *= srgb_to_linear(t.rgb);
        p.alpha *= t.a;
    }
    if (d.tex[2 * TEX_METALLIC_ROUGHNESS].w >= 0.0) {
        vec4 t = material_texture(m, TEX_METALLIC_ROUGHNESS, uv, uv_lod);
        p.roughness *= t.g;
        p.metallic *= t.b;
    }
    if (d.tex[2 * TEX_EMISSIVE].w >= 0.0)
        p.emissive *= srgb_to_linear(material_texture(m, TEX_EMISSIVE, uv, uv_lod).rgb);
    if (d.tex[2 * TEX_OCCLUSION].w >= 0.0)
        p.occlusion = mix(1.0, material_texture(m, TEX_OCCLUSION, uv, uv_lod).r, d.tex[2 * TEX_OCCLUSION + 1].w);
    if (d.tex[2 * TEX_SPECULAR].w >= 0.0)
        p.specular *= material_texture(m, TEX_SPECULAR, uv, uv_lod).a;
    if (d.tex[2 * TEX_SPECULAR_COLOR].w >= 0.0)
        p.specular_color *= srgb_to_linear(material_texture(m, TEX_SPECULAR_COLOR, uv, uv_lod).rgb);
#if SCENE_HAS_TRANSMISSION
    if (d.tex[2 * TEX_TRANSMISSION].w >= 0.0)
        p.transmission *= material_texture(m, TEX_TRANSMISSION, uv, uv_lod).r;
#endif
#endif
    return p;
}

MaterialParams material_params(uint m, vec2 uv) { return material_params_at(m, uv, UV_LOD_FINEST); }

#if SCENE_HAS_ALPHA_MASK || SCENE_HAS_ALPHA_BLEND
// Alpha of material m at uv: the factor times the base colour texture's alpha (level 0).
float material_alpha(uint m, vec2 uv) {
    float a = scene_materials[m].base_color.a;
#if SCENE_HAS_TEXTURES
    if (scene_materials[m].tex[2 * TEX_BASE_COLOR].w >= 0.0) a *= material_texture(m, TEX_BASE_COLOR, uv, UV_LOD_FINEST).a;
#endif
    return a;
}
#endif

// Alpha of material m at uv against its cutoff (MASK); other modes always pass.
bool material_alpha_passes(uint m, vec2 uv) {
#if SCENE_HAS_ALPHA_MASK
    if (scene_materials[m].flags.y != ALPHA_MODE_MASK) return true;
    return material_alpha(m, uv) >= scene_materials[m].emission_cutoff.a;
#else
    return true;
#endif
}

#if SCENE_HAS_ALPHA_BLEND
// alphaMode BLEND as stochastic transparency (Enderton et al. 2010): a surface of alpha a is there
// for a ray or a fragment with probability a, so that the mean over frames is a * front +
// (1 - a) * behind and a shadow ray through it is blocked with probability a. `seed` and `index`
// are a path's Rng state and sample index (sampling.glsl; the index runs over the frames), `key`
// names the surface met and the ray along the path (alpha_blend_key): u is the Owen-scrambled van
// der Corput point of the index under a scramble of its own, so a key's decisions over
// consecutive frames are stratified (0.3 is met 3 times in 10 frames, give or take one) and two
// keys' are independent.
float alpha_blend_u(uint seed, uint index, uint key) {
    return sobol_1d(index, hash_combine(seed, pcg_hash(key ^ 0xA511E9B3u)));
}

// The key of a surface of `material` on `instance` met at distance t along ray number `ray` of a
// path. Not the triangle: a ray through a shared edge hits both triangles (ray_query.glsl widens
// edges), and two draws there would show the surface with probability 1 - (1 - a)^2. t is
// bucketed at 1/256 of an octave (0.27%): the two hits of an edge fall in one bucket but for
// rounding at a bucket's border (~1e-6 / 0.0027 of edge rays), and two layers of one material
// closer than that along the ray share a draw.
uint alpha_blend_key(uint instance, uint material, float t, uint ray) {
    uint bucket = uint(int(floor(log2(max(t, 1e-30)) * 256.0)));
    return pcg_hash(bucket + pcg_hash(material + pcg_hash(instance + pcg_hash(ray))));
}

// Whether material m at uv is there for the key: always unless BLEND, then with probability
// alpha (alpha 1: always, 0: never; u < 1).
bool material_blend_passes(uint m, vec2 uv, uint seed, uint index, uint key) {
    if (scene_materials[m].flags.y != ALPHA_MODE_BLEND) return true;
    return alpha_blend_u(seed, index, key) < material_alpha(m, uv);
}
#endif

// ---- triangles ------------------------------------------------------------------------------

// The render-space normal of the side the winding makes the front, for object-space vertices
// a, b, c of instance i (unnormalised; zero for a degenerate triangle). Ray hits and the raster
// G-buffer both take a triangle's front from it (glTF: a mirroring transform keeps the front).
vec3 instance_face_normal(uint i, vec3 a, vec3 b, vec3 c) {
    return instance_normal_to_render(i, cross(b - a, c - a));
}

vec2 triangle_uv(uint tri, vec2 bary) {
    vec3 w = vec3(1.0 - bary.x - bary.y, bary);
    VertexData a = scene_vertices[scene_indices[3u * tri]];
    VertexData b = scene_vertices[scene_indices[3u * tri + 1u]];
    VertexData c = scene_vertices[scene_indices[3u * tri + 2u]];
    return w.x * vec2(a.position_u.w, a.normal_v.w) + w.y * vec2(b.position_u.w, b.normal_v.w)
         + w.z * vec2(c.position_u.w, c.normal_v.w);
}

// ---- raster: vertex pulling -------------------------------------------------------------------

struct RasterVertex {
    vec3 position;   // render space
    vec3 normal;     // render space, normalised
    vec2 uv;
    vec4 tangent;    // render space xyz, handedness w (0 without normal maps)
    vec3 face_normal;   // the triangle's instance_face_normal (the front side; unnormalised)
    uint material;
    uint triangle;   // scene triangle
    bool convex;     // its whole mesh lies behind it (TRIANGLE_CONVEX_BIT)
};

RasterVertex scene_raster_vertex(uint instance, int vertex_id) {
    RasterVertex r;
    uint vi = scene_indices[uint(vertex_id)];
    VertexData v = scene_vertices[vi];
    r.position = instance_point_to_render(instance, v.position_u.xyz);
    r.normal = safe_normalize(instance_normal_to_render(instance, v.normal_v.xyz), vec3(0, 1, 0));
    r.uv = vec2(v.position_u.w, v.normal_v.w);
    r.tangent = vec4(0.0);
#if SCENE_HAS_NORMAL_MAPS
    vec4 t = scene_tangents[vi];
    r.tangent = vec4(safe_normalize(instance_vector_to_render(instance, t.xyz), vec3(1, 0, 0)), t.w);
#endif
    r.triangle = uint(vertex_id) / 3u;
    r.face_normal = instance_face_normal(instance, scene_vertices[scene_indices[3u * r.triangle]].position_u.xyz,
                                         scene_vertices[scene_indices[3u * r.triangle + 1u]].position_u.xyz,
                                         scene_vertices[scene_indices[3u * r.triangle + 2u]].position_u.xyz);
    uint word = scene_triangle_materials[r.triangle];
    r.material = triangle_word_material(word);
    r.convex = triangle_word_convex(word);
    return r;
}

// ---- ray hits -----------------------------------------------------------------------------------

// A closest hit (ray_query.glsl fills it): instance, mesh-local triangle, barycentrics of
// vertices 1 and 2, distance t along the (unnormalised ok) ray direction.
struct Hit {
    float t;
    vec2 barycentrics;
    uint instance;
    uint primitive;
};

struct SurfacePoint {
    vec3 position;           // render space
    vec3 normal;             // shading normal (normal map applied), on geometric_normal's side
    vec3 geometric_normal;   // faces the incoming ray
    vec2 uv;
    uint material;
    bool front_face;         // the ray hit the side the winding makes the front
    uint triangle;           // scene triangle
    float uv_lod;            // log2 of the ray cone's footprint in uv units (UV_LOD_FINEST: none)
    // the hit's instance where this is a front face with its whole mesh behind it, so that rays
    // leaving on geometric_normal's side may skip the instance (ray_query.glsl), else SCENE_NO_INSTANCE
    uint exit_instance;
};

vec3 apply_normal_map(SurfacePoint s, uint tri, vec3 w, uint instance) {
#if SCENE_HAS_NORMAL_MAPS
    uint m = s.material;
    if (scene_materials[m].tex[2 * TEX_NORMAL].w < 0.0) return s.normal;
    vec4 t = w.x * scene_tangents[scene_indices[3u * tri]] + w.y * scene_tangents[scene_indices[3u * tri + 1u]]
           + w.z * scene_tangents[scene_indices[3u * tri + 2u]];
    vec3 tw = instance_vector_to_render(instance, t.xyz);
    tw = tw - s.normal * dot(s.normal, tw);
    if (dot(tw, tw) < 1e-20) return s.normal;
    tw = normalize(tw);
    vec3 bw = cross(s.normal, tw) * (t.w < 0.0 ? -1.0 : 1.0);
    vec3 tn = material_texture(m, TEX_NORMAL, s.uv, s.uv_lod).xyz * 2.0 - 1.0;
    tn.xy *= scene_materials[m].tex[2 * TEX_NORMAL + 1].w;
    return safe_normalize(tn.x * tw + tn.y * bw + tn.z * s.normal, s.normal);
#else
    return s.normal;
#endif
}

// The hit surface; `cone_width` is the ray cone's width at the hit (render-space units, 0: no
// cone), from which uv_lod follows: log2(width / |cos|) + log2 of uv units per render-space unit.
SurfacePoint surface_at_cone(Hit h, vec3 dir, float cone_width) {
    SurfacePoint s;
    uint tri = scene_triangle(h.instance, h.primitive);
    vec3 w = vec3(1.0 - h.barycentrics.x - h.barycentrics.y, h.barycentrics);
    VertexData a = scene_vertices[scene_indices[3u * tri]];
    VertexData b = scene_vertices[scene_indices[3u * tri + 1u]];
    VertexData c = scene_vertices[scene_indices[3u * tri + 2u]];
    vec3 p = w.x * a.position_u.xyz + w.y * b.position_u.xyz + w.z * c.position_u.xyz;
    s.position = instance_point_to_render(h.instance, p);
    vec3 ng = instance_face_normal(h.instance, a.position_u.xyz, b.position_u.xyz, c.position_u.xyz);
    vec3 n = instance_normal_to_render(h.instance, w.x * a.normal_v.xyz + w.y * b.normal_v.xyz + w.z * c.normal_v.xyz);
    s.geometric_normal = safe_normalize(ng, -normalize(dir));
    s.normal = safe_normalize(n, s.geometric_normal);
    s.front_face = dot(s.geometric_normal, dir) < 0.0;
    if (!s.front_face) s.geometric_normal = -s.geometric_normal;
    // the shading normal on the geometric normal's side, whatever way the vertex normals point
    // (flipped by an exporter): the raster G-buffer's rule too
    if (dot(s.normal, s.geometric_normal) < 0.0) s.normal = -s.normal;
    s.uv = w.x * vec2(a.position_u.w, a.normal_v.w) + w.y * vec2(b.position_u.w, b.normal_v.w)
         + w.z * vec2(c.position_u.w, c.normal_v.w);
    uint word = scene_triangle_materials[tri];
    s.material = triangle_word_material(word);
    s.exit_instance = exit_instance_seen(triangle_word_convex(word) ? h.instance : SCENE_NO_INSTANCE, s.front_face);
    s.triangle = tri;
    s.uv_lod = UV_LOD_FINEST;
#if SCENE_HAS_TEXTURES
    if (cone_width > 0.0) {
        vec2 duv1 = vec2(b.position_u.w, b.normal_v.w) - vec2(a.position_u.w, a.normal_v.w);
        vec2 duv2 = vec2(c.position_u.w, c.normal_v.w) - vec2(a.position_u.w, a.normal_v.w);
        float uv_area = abs(duv1.x * duv2.y - duv1.y * duv2.x);
        float area = length(cross(instance_vector_to_render(h.instance, b.position_u.xyz - a.position_u.xyz),
                                  instance_vector_to_render(h.instance, c.position_u.xyz - a.position_u.xyz)));
        float cos_theta = abs(dot(s.geometric_normal, dir)) * inversesqrt(max(dot(dir, dir), 1e-30));
        if (uv_area > 0.0 && area > 0.0)
            s.uv_lod = log2(cone_width / max(cos_theta, 1e-3)) + 0.5 * log2(uv_area / area);
    }
#endif
#if SCENE_HAS_NORMAL_MAPS
    s.normal = apply_normal_map(s, tri, w, h.instance);
#endif
    return s;
}

SurfacePoint surface_at(Hit h, vec3 dir) { return surface_at_cone(h, dir, 0.0); }

// A ray cone's spread angle after a bounce that sampled its direction with solid-angle `pdf`:
// the lobe adds ~1/sqrt(pdf) radians (a mirror, delta, adds nothing).
float cone_spread_after_bounce(float spread, float pdf, bool delta) {
    return delta ? spread : spread + inversesqrt(max(pdf, 1e-4));
}
