// Unidirectional path tracing from a path vertex: next-event estimation (lights.glsl) combined
// with BSDF sampling (bsdf.glsl) by the power heuristic, Russian roulette, delta lobes, and
// transmission: refraction through volumes (Beer-Lambert absorption inside them, the medium
// tracked by which face a refracted path enters or leaves) and thin-walled surfaces.
// Bounce k does NEE at vertex k and continues with a BSDF sample whose hit adds MIS-weighted
// emission, so max_bounces = 1 is complete direct light and 0 is emission only.
// Uniforms: pt_max_bounces, pt_rr_start.
#pragma once
#include "path_vertex.glsl"
#include "lights.glsl"
#include "ray_query.glsl"
#include "nonfinite.glsl"

uniform int pt_max_bounces;
uniform int pt_rr_start;

// A path between its vertices: what it has gathered, its throughput, the absorption of the medium
// it travels through (0: air), and with `split` what the denoisers' lobe split needs: the diffuse
// part of the first vertex's light sample, all that sample added, and the diffuse share of the
// first BSDF sample's weight (f_d / pdf over f / pdf).
struct PtPath {
    vec3 radiance;
    vec3 beta;
    vec3 medium;
    vec3 first_diffuse;
    vec3 first_total;
    vec3 share;
};

PtPath pt_path_begin() {
    PtPath path;
    path.radiance = vec3(0.0);
    path.beta = vec3(1.0);
    path.medium = vec3(0.0);
    path.first_diffuse = vec3(0.0);
    path.first_total = vec3(0.0);
    path.share = vec3(0.0);
    return path;
}

// What a vertex asks of the rays: its light sample's shadow ray with the light it brings if
// unoccluded (nee_dist < 0: none), and its BSDF sample's ray (`scattered` false: the path ends
// once the shadow ray is answered), with what the answer at the hit needs.
struct PtRays {
    vec3 nee;            // the light sample's contribution (throughput included)
    vec3 nee_diffuse;    // split: its diffuse part (first vertex)
    vec3 nee_dir;
    float nee_dist;
    vec3 pos;            // the vertex; ray origins are offset from it along ng
    vec3 ng;
    uint exit_instance;  // what the shadow ray and a reflected BSDF ray skip (PathVertex.exit_instance)
    vec3 dir;            // the BSDF sample
    float pdf;
    bool scattered;
    bool delta;
    bool transmitted;
    float cone_width;    // the path's ray cone at pos
    float cone_spread;
};

// No rays: no light sample, no BSDF sample.
PtRays pt_no_rays() {
    PtRays r;
    r.nee = vec3(0.0);
    r.nee_diffuse = vec3(0.0);
    r.nee_dir = vec3(0.0);
    r.nee_dist = -1.0;
    r.pos = vec3(0.0);
    r.ng = vec3(0.0);
    r.exit_instance = SCENE_NO_INSTANCE;
    r.dir = vec3(0.0);
    r.pdf = 0.0;
    r.scattered = false;
    r.delta = false;
    r.transmitted = false;
    r.cone_width = 0.0;
    r.cone_spread = 0.0;
    return r;
}

// Vertex s at `bounce` (everything before its rays, so that nothing of the BSDF is live while
// they are traced): the light sample and its value, the BSDF sample, the medium entered, the
// throughput after it and Russian roulette.
PtRays pt_vertex(inout PtPath path, PathVertex s, int bounce, inout Rng rng, const bool split) {
    PtRays r = pt_no_rays();
    r.pos = s.pos;
    r.ng = s.ng;
    r.exit_instance = s.exit_instance;
    r.cone_width = s.cone_width;
    r.cone_spread = s.cone_spread;
#if SCENE_HAS_LIGHTS
    LightSample ls = sample_light(s.pos, rng_next3(rng));
    if (ls.valid && dot(ls.direction, s.ng) > 0.0) {
        vec3 f = bsdf_eval(s.bsdf, s.n, s.v, ls.direction);
        if (max3(f) > 0.0) {
            float w = ls.pdf > 0.0 ? power_heuristic(ls.pdf, bsdf_pdf(s.bsdf, s.n, s.v, ls.direction)) : 1.0;
            r.nee = path.beta * f * ls.weight * w;
            if (split && bounce == 0)
                r.nee_diffuse = bsdf_eval_lobes(s.bsdf, s.n, s.v, ls.direction, BSDF_LOBES_DIFFUSE) * ls.weight * w;
            shadow_ray(s.pos, offset_ray_origin(s.pos, s.ng), ls, r.nee_dir, r.nee_dist);   // traced from there
        }
    }
#endif
    BsdfSample bs;
    bool scattered = bsdf_sample(s.bsdf, s.n, s.v, rng_next3(rng), bs);
    // the sampled side must agree with the geometric surface (shading normals may not)
    float side = dot(bs.l, s.ng);
    if (scattered && (bs.transmitted ? side >= 0.0 : side <= 0.0)) scattered = false;
    if (scattered && split && bounce == 0 && !bs.delta && !bs.transmitted)
        path.share = clamp(bsdf_eval_lobes(s.bsdf, s.n, s.v, bs.l, BSDF_LOBES_DIFFUSE) / (bs.pdf * max(bs.weight, vec3(1e-30))),
                           vec3(0.0), vec3(1.0));
    if (scattered && bs.transmitted && !s.bsdf.thin) path.medium = s.bsdf.inside ? vec3(0.0) : s.attenuation;
    r.dir = bs.l;
    r.pdf = bs.pdf;
    r.delta = bs.delta;
    r.transmitted = bs.transmitted;
    if (scattered) {
        path.beta *= bs.weight;
        if (!(max3(path.beta) > 0.0)) scattered = false;
    }
    if (scattered && bounce >= pt_rr_start) {
        float q = clamp(max3(path.beta), 0.05, 1.0);
        if (rng_next(rng) >= q) scattered = false;
        else path.beta /= q;
    }
    r.scattered = scattered;
    return r;
}

// The shadow ray's answer at `bounce`.
void pt_shadow_answer(inout PtPath path, PtRays r, bool occluded, int bounce, const bool split) {
    if (r.nee_dist >= 0.0 && !occluded) {
        path.radiance += r.nee;
        if (split && bounce == 0) path.first_diffuse = r.nee_diffuse;
    }
    if (split && bounce == 0) path.first_total = path.radiance;
}

// The BSDF ray's answer at `bounce` (found: its hit): the light it brings (the environment or an
// emitter, shared with the light sample by the power heuristic), the medium's absorption, and
// the next vertex `s`; false when the path ends there.
bool pt_ray_answer(inout PtPath path, PtRays r, bool found, Hit hit, int bounce, out PathVertex s) {
    // The light sample covers only the side of the surface that the geometric normal faces, so a
    // transmitted direction (below it) has no light-sampling strategy to share with: its
    // emission takes the whole weight, as a delta lobe's does.
    bool whole = r.delta || r.transmitted;
    if (!found) {
        float w = whole ? 1.0 : power_heuristic(r.pdf, environment_light_pdf(r.dir));
        path.radiance += path.beta * environment_radiance(r.dir) * w;
        return false;
    }
    if (max3(path.medium) > 0.0) path.beta *= exp(-path.medium * hit.t);
    float spread = cone_spread_after_bounce(r.cone_spread, r.pdf, r.delta);
    SurfacePoint sp;
    MaterialParams mp;
#if SCENE_HAS_EMISSIVE_TRIANGLES
    bool last = bounce == pt_max_bounces - 1;
    if (last) {   // the path ends here: only the hit's emission counts
        sp = surface_at_cone(hit, r.dir, r.cone_width + hit.t * spread);
        mp = material_params_at(sp.material, sp.uv, sp.uv_lod);
    } else {
        s = path_vertex_at_hit(hit, r.dir, r.cone_width + hit.t * spread, spread, sp, mp);
    }
    if (max3(mp.emissive) > 0.0 && (sp.front_face || mp.double_sided)) {
        float w = whole ? 1.0 : power_heuristic(r.pdf, emissive_light_pdf(sp, hit.instance, r.pos));
        path.radiance += path.beta * mp.emissive * w;
    }
    return !last;
#else
    if (bounce == pt_max_bounces - 1) return false;
    s = path_vertex_at_hit(hit, r.dir, r.cone_width + hit.t * spread, spread, sp, mp);
    return true;
#endif
}

// What a finished path brought, as the part the first vertex's diffuse lobe reflects and the
// rest (split false: all of it in `specular`).
void pt_path_parts(PtPath path, const bool split, out vec3 diffuse, out vec3 specular) {
    diffuse = split ? path.first_diffuse + path.share * (path.radiance - path.first_total) : vec3(0.0);
    specular = path.radiance - diffuse;
}

// Radiance arriving at the previous vertex from s (emission of s itself excluded), as the part
// s's diffuse lobe reflects and the rest (with `split` false all of it is in `specular`, and the
// compiler drops the split): the megakernel, every bounce's rays traced in one invocation. The
// wavefront form (passes/path_tracer/pt_wave_*.comp) runs the same steps with the rays in their
// own dispatches.
void pt_trace_parts(PathVertex s, inout Rng rng, const bool split, out vec3 diffuse, out vec3 specular) {
    PtPath path = pt_path_begin();
    for (int bounce = 0; bounce < pt_max_bounces; ++bounce) {
        PtRays r = pt_vertex(path, s, bounce, rng, split);
        bool occluded = r.nee_dist >= 0.0 && trace_occluded(offset_ray_origin(r.pos, r.ng), r.nee_dir, r.nee_dist,
                                                                r.exit_instance);
        pt_shadow_answer(path, r, occluded, bounce, split);
        if (!r.scattered) break;
        Hit hit;
        bool found = trace_closest(offset_ray_origin(r.pos, r.transmitted ? -r.ng : r.ng), r.dir, 1e30,
                                   r.transmitted ? SCENE_NO_INSTANCE : r.exit_instance, hit);
        if (!pt_ray_answer(path, r, found, hit, bounce, s)) break;
    }
    pt_path_parts(path, split, diffuse, specular);
}

vec3 pt_trace_from(PathVertex s, inout Rng rng) {
    vec3 diffuse, specular;
    pt_trace_parts(s, rng, false, diffuse, specular);
    return specular;
}

// A sample's radiance made safe: NaN/Inf dropped (returns 0, counted: nonfinite.glsl), optional
// clamp (> 0) per channel.
vec3 pt_finite(vec3 c, float clamp_max) {
    c = nonfinite_scrub(c);
    return clamp_max > 0.0 ? min(c, vec3(clamp_max)) : c;
}
