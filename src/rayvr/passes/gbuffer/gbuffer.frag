// G-buffer fragment stage: material parameters, normals facing the viewer, effect id, motion;
// the outputs (one per channel, in the table's order) come from gbuffer_channels.glsl.
#define SCENE_MATERIAL_GRADIENTS 1
#define GBUF_WRITER 1
#define GBUF_RASTER_WRITER 1
#include "views.glsl"
#include "scene.glsl"
#include "gbuffer.glsl"

in vec3 v_pos;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_tangent;
flat in vec3 v_face_normal;
flat in uint v_material;
flat in uint v_convex_instance;
flat in uint v_view;
#if SCENE_HAS_ALPHA_BLEND
flat in uint v_instance;
#endif


void main() {
    material_uv_dx = dFdx(v_uv);   // here, in uniform control flow (scene.glsl SCENE_MATERIAL_GRADIENTS)
    material_uv_dy = dFdy(v_uv);
    MaterialParams m = material_params(v_material, v_uv);
#if SCENE_HAS_ALPHA_MASK
    if (m.alpha_mode == ALPHA_MODE_MASK && m.alpha < scene_materials[v_material].emission_cutoff.a) discard;
#endif
#if SCENE_HAS_ALPHA_BLEND
    // stochastic transparency: drawn with probability alpha, by GBufferRT's decision for this
    // pixel's ray (ray 1 of its generator, t from the near plane; scene.glsl alpha_blend_u)
    if (m.alpha_mode == ALPHA_MODE_BLEND) {
        Rng rng = rng_init(uvec2(gl_FragCoord.xy), view_global_index(v_view), frame_index(), RNG_SALT_GBUFFER);
        vec3 ray = v_pos - views[v_view].eye.xyz;
        float dist = length(ray);
        float t = dist - views[v_view].clip.x * dist / -(views[v_view].view * vec4(ray, 0.0)).z;
        if (!(alpha_blend_u(rng.state, rng.index, alpha_blend_key(v_instance, v_material, t, 1u)) < m.alpha)) discard;
    }
#endif
    vec3 eye = views[v_view].eye.xyz;
    vec3 to_eye = eye - v_pos;
    // The triangle's own normal (as a ray hit's, scene.glsl surface_at_cone): which side is the
    // front, and the geometric normal without the rounding of screen-space derivatives.
    vec3 ng = safe_normalize(v_face_normal, normalize(to_eye));
    bool front_face = dot(ng, to_eye) >= 0.0;
    if (!front_face) ng = -ng;
    vec3 n = safe_normalize(v_normal, ng);
    if (dot(n, ng) < 0.0) n = -n;   // back face seen: shade the side facing the viewer
#if SCENE_HAS_NORMAL_MAPS
    if (scene_materials[v_material].tex[2 * TEX_NORMAL].w >= 0.0 && dot(v_tangent.xyz, v_tangent.xyz) > 0.0) {
        vec3 t = safe_normalize(v_tangent.xyz - n * dot(n, v_tangent.xyz), vec3(1, 0, 0));
        vec3 b = cross(n, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0);
        vec3 tn = material_texture(v_material, TEX_NORMAL, v_uv, UV_LOD_FINEST).xyz * 2.0 - 1.0;
        tn.xy *= scene_materials[v_material].tex[2 * TEX_NORMAL + 1].w;
        n = safe_normalize(tn.x * t + tn.y * b + tn.z * n, n);
    }
#endif
    gbuf_output(gbuf_encode(v_view, v_pos, n, ng, front_face, m, v_material,
                            exit_instance_seen(v_convex_instance, front_face)));   // one output per channel
}
