// G-buffer vertex stage: vertex pulling from the GPU scene (scene.glsl), one draw for every view.
// Layered: GpuScene.draw(program, views) draws each instance `views` times; gl_InstanceID is the
// view and gl_Layer its layer. Multiview: gl_ViewID_OVR is the view.
#if RAYVR_MULTIVIEW
#extension GL_OVR_multiview2 : require
#else
#extension GL_ARB_shader_viewport_layer_array : require
#endif
#include "views.glsl"
#include "scene.glsl"

#if RAYVR_MULTIVIEW
layout(num_views = VIEW_COUNT) in;
#define CURRENT_VIEW gl_ViewID_OVR
#else
#define CURRENT_VIEW uint(gl_InstanceID)
#endif

in uint rayvr_instance;

out vec3 v_pos;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_tangent;
flat out vec3 v_face_normal;
flat out uint v_material;
flat out uint v_convex_instance;   // the instance where the triangle has its whole mesh behind it
flat out uint v_view;
#if SCENE_HAS_ALPHA_BLEND
flat out uint v_instance;
#endif

void main() {
    uint view = CURRENT_VIEW;
    RasterVertex r = scene_raster_vertex(rayvr_instance, gl_VertexID);
    v_pos = r.position;
    v_normal = r.normal;
    v_uv = r.uv;
    v_tangent = r.tangent;
    v_face_normal = r.face_normal;
    v_material = r.material;
    v_convex_instance = r.convex ? rayvr_instance : SCENE_NO_INSTANCE;
    v_view = view;
#if SCENE_HAS_ALPHA_BLEND
    v_instance = rayvr_instance;
#endif
    gl_Position = views[view].view_proj * vec4(r.position, 1.0);
    // TAA jitter: sample at pixel centre + jitter (as the ray passes do), so the geometry moves by
    // -jitter; motion vectors (gbuf_encode) use the unjittered matrices.
    gl_Position.xy -= views[view].jitter.xy * (2.0 / views[view].clip.zw) * gl_Position.w;
#if !RAYVR_MULTIVIEW
    gl_Layer = int(view);
#endif
}
