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
    uint exit_instance;  // what rays leaving on ng's side may skip (SurfacePoint.exit_instance)
};

// Shading-normal adaptation (Keller et al. 2017, "The Iray Light Transport Simulation and
// Rendering System", A.3): where the mirror direction of v about the shading normal n falls
// below the geometric surface (ng, facing v), as at the silhouettes of a coarse mesh with smooth
// normals, n is bent towards ng until that direction is just above the surface. Without it the
// BSDF's samples there point into the surface and are dropped: a smooth sphere of 80 triangles
// lost most of its reflection at the rim. Elsewhere n is returned unchanged.
const float SHADING_ADAPT_HEIGHT = 0.01;   // the lowest the mirror direction may lie (its cosine to ng)
vec3 adapt_shading_normal(vec3 n, vec3 ng, vec3 v) {
    float hv = dot(v, ng);
    // never higher than the geometric mirror direction (whose height is v's): a flat surface
    // (n = ng) seen at a grazing angle keeps its normal
    float h = min(SHADING_ADAPT_HEIGHT, hv);
    vec3 r = reflect(-v, n);
    float a = dot(r, ng);
    if (a >= h || hv <= 0.0) return n;
    vec3 t = r - a * ng;   // the mirror direction's tangential part
    float lt = length(t);
    if (!(lt > 1e-6)) return ng;
    vec3 raised = t * (sqrt(1.0 - h * h) / lt) + h * ng;
    return normalize(v + raised);   // the half vector: v mirrors to `raised` about it
}

// What a ray leaving s along dir may skip: s's exit instance if dir leaves on ng's side.
uint path_vertex_skip(PathVertex s, vec3 dir) { return dot(dir, s.ng) > 0.0 ? s.exit_instance : SCENE_NO_INSTANCE; }

// The vertex where `hit` of a ray along `dir` lies; `cone_width` is the ray cone's width at the
// hit. `sp` and `mp` return the surface and its material (emission, flags) for the caller.
PathVertex path_vertex_at_hit(Hit hit, vec3 dir, float cone_width, float cone_spread,
                              out SurfacePoint sp, out MaterialParams mp) {
    sp = surface_at_cone(hit, dir, cone_width);
    mp = material_params_at(sp.material, sp.uv, sp.uv_lod);
    PathVertex s;
    s.pos = sp.position;
    s.ng = sp.geometric_normal;
    s.v = -dir;
    s.n = adapt_shading_normal(sp.normal, s.ng, s.v);
    s.bsdf = bsdf_params(mp);
    // a back face of a volume: the ray comes from inside it (refraction goes out, TIR possible)
    bsdf_set_side(s.bsdf, !sp.front_face && mp.volume);
    bsdf_set_view(s.bsdf, s.n, s.v);
    s.attenuation = mp.attenuation;
    s.cone_width = cone_width;
    s.cone_spread = cone_spread;
    s.exit_instance = sp.exit_instance;
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

// The vertex of G-buffer texel g seen along unit v (towards the viewer), with view `view`'s
// primary ray cone.
PathVertex path_vertex_at_gbuffer_seen(GSurface g, uint view, vec3 v) {
    PathVertex s;
    s.pos = g.pos;
    s.ng = g.ng;
    s.v = v;
    s.n = adapt_shading_normal(g.n, s.ng, s.v);
    MaterialParams m = gbuf_material_params(g);
    s.bsdf = bsdf_params(m);
    bsdf_set_side(s.bsdf, !g.front_face && m.volume);   // as path_vertex_at_hit: inside a volume
    bsdf_set_view(s.bsdf, s.n, s.v);
    s.attenuation = m.attenuation;
    s.cone_spread = view_pixel_spread(view);
    s.cone_width = distance(views[view].eye.xyz, g.pos) * s.cone_spread;
    s.exit_instance = g.exit_instance;
    return s;
}

// The vertex of G-buffer texel g, seen from view `view`'s eye (its primary ray's cone).
PathVertex path_vertex_at_gbuffer(GSurface g, uint view) {
    return path_vertex_at_gbuffer_seen(g, view, normalize(views[view].eye.xyz - g.pos));
}
#endif
