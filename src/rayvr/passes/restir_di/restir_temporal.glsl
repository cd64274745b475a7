// ReSTIR DI's temporal reuse (restir_temporal.comp, or fused into restir_candidates.comp where that
// traces no ray): a pixel's reservoir combined with last frame's temporal one where the G-buffer's
// motion vector says this surface was (the nearest pixel, when the disocclusion test of
// glsl/reprojection.glsl passes), its confidence capped at RESTIR_MAX_HISTORY, by generalized RIS
// with pairwise MIS (restir_di.glsl). Last frame's target is evaluated at this frame's surface seen
// from where last frame's eye was (the direction the history recorded): a static view evaluates it
// exactly, and under head motion the view-dependent lobes move with it. Include after
// restir_stage.glsl.
#pragma once

layout(rgba32ui) readonly uniform uimage2DArray history_in;   // last frame's reservoirs of this stage
layout(rgba32ui) readonly uniform uimage2DArray surface_in;   // and the surfaces they were made at
uniform bool restir_history_valid;   // false on the first frame, after reset() and lighting edits

// Pixel p's reservoir c (its target at p: c_at_c; p's visibility hints `hints`) combined with its
// history; c where there is none. Last frame's target takes the hints of the pixel it was made at.
Reservoir restir_temporal_reuse(ivec3 p, ivec3 size, GSurface g, PathVertex s, uint hints, Reservoir c, float c_at_c) {
    vec2 then_pixel = reprojected_pixel(p);
    ivec3 q = ivec3(ivec2(floor(then_pixel)), p.z);
    if (!restir_history_valid || !pixel_inside(q.xy, size.xy)) return c;
    ReservoirSurface then = reservoir_surface_unpack(imageLoad(surface_in, q));
    float depth = gbuf_fetch_posW(p).w;
    float then_depth = reprojected_depth(uint(p.z), g.pos);
    float tolerance = reprojection_tolerance(then_depth, gbuf_depth_gradient(p, depth, size.xy));
    if (!(then.depth > 0.0) || !reprojection_matches(then.depth, oct_unpack_snorm16(then.normal), then.word,
                                                     then_depth, g.n, gbuf_fetch_effect(p), tolerance))
        return c;
    Reservoir h = reservoir_unpack(imageLoad(history_in, q));
    h.confidence = min(h.confidence, float(RESTIR_MAX_HISTORY));
    bool specular_traced = restir_specular_traced(g);
    PathVertex s_then = path_vertex_at_gbuffer_seen(g, uint(p.z), oct_unpack_snorm16(then.view_dir));
    LightSample lc = light_id_eval(reservoir_light_id(c), s.pos);
    LightSample lh = light_id_eval(reservoir_light_id(h), s.pos);
    uvec2 c_id = reservoir_light_id(c), h_id = reservoir_light_id(h);
    uint then_hints = restir_hints_at(q);
    float c_at_h = restir_target(s, specular_traced, lh, restir_hint(hints, h_id));
    float then_at_c = restir_target(s_then, specular_traced, lc, restir_hint(then_hints, c_id));
    float then_at_h = restir_target(s_then, specular_traced, lh, restir_hint(then_hints, h_id));
    Rng rng = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT_RESTIR_TEMPORAL);
    ReservoirStream pick = stream_begin(rng_next(rng));
    stream_add(pick, c_id, pair_weight(c.confidence, c_at_c, h.confidence, then_at_c) * c_at_c * c.weight, c_at_c);
    stream_add(pick, h_id, pair_weight(h.confidence, then_at_h, c.confidence, c_at_h) * c_at_h * h.weight, c_at_h);
    float m = c.confidence + h.confidence;
    return stream_reservoir(pick, m, m);
}
