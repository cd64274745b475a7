// A scattering vertex of a path, where every ray pass starts and continues: from a ray hit
// (path_vertex_at_hit) or from the G-buffer (path_vertex_at_gbuffer, with GBUF_READER and
// views.glsl). One construction for the path tracer, reflections and every pass to come.
#pragma once
#include "scene.glsl"
#include "bsdf.glsl"

struct PathVertex {
    vec3 pos;            // render space
    vec3 n;              // shading normal facing v
    vec3 ng;             // geometric normal facing v
    vec3 v;              // towards the previous vertex (the viewer)
    BsdfParams bsdf;
    vec3 attenuation;    // absorption per metre inside the material's volume (transmission)
    float cone_width;    // the path's ray cone at pos (texture level of detail)
    float cone_spread;   // and its spread angle
};

// The vertex where `hit` of a ray along `dir` lies; `cone_width` is the ray cone's width at the
// hit. `sp` and `mp` return the surface and its material (emission, flags) for the caller.
PathVertex path_vertex_at_hit(Hit hit, vec3 dir, float cone_width, float cone_spread,
                              out SurfacePoint sp, out MaterialParams mp) {
    sp = surface_at_cone(hit, dir, cone_width);
    mp = material_params_at(sp.material, sp.uv, sp.uv_lod);
    PathVertex s;
    s.pos = sp.position;
    s.n = sp.normal;
    s.ng = sp.geometric_normal;
    s.v = -dir;
    s.bsdf = bsdf_params(mp);
    // a back face of a volume: the ray comes from inside it (refraction goes out, TIR possible)
    bsdf_set_side(s.bsdf, !sp.front_face && mp.volume);
    bsdf_set_view(s.bsdf, s.n, s.v);
    s.attenuation = mp.attenuation;
    s.cone_width = cone_width;
    s.cone_spread = cone_spread;
    return s;
}

#ifdef GBUF_READER
#include "views.glsl"
#include "gbuffer.glsl"

// The material of a G-buffer texel: what the G-buffer stores (textures already applied), the
// rest from its material's table entry.
MaterialParams gbuf_material_params(GSurface g) {
    MaterialParams m = material_factors(g.material);
    m.base_color = g.base_color;
    m.alpha = g.alpha;
    m.metallic = g.metallic;
    m.roughness = g.roughness;
    m.emissive = g.emissive;
    return m;
}

// The vertex of G-buffer texel g, seen from view `view`'s eye (its primary ray's cone).
PathVertex path_vertex_at_gbuffer(GSurface g, uint view) {
    PathVertex s;
    s.pos = g.pos;
    s.n = g.n;
    s.ng = g.ng;
    s.v = normalize(views[view].eye.xyz - g.pos);
    MaterialParams m = gbuf_material_params(g);
    s.bsdf = bsdf_params(m);
    bsdf_set_side(s.bsdf, !g.front_face && m.volume);   // as path_vertex_at_hit: inside a volume
    bsdf_set_view(s.bsdf, s.n, s.v);
    s.attenuation = m.attenuation;
    s.cone_spread = view_pixel_spread(view);
    s.cone_width = distance(views[view].eye.xyz, g.pos) * s.cone_spread;
    return s;
}
#endif
