// ReSTIR DI stage 3, spatial reuse: this pixel's reservoir (canonical) and those of up to
// RESTIR_SPATIAL_SAMPLES pixels drawn uniformly within RESTIR_SPATIAL_RADIUS pixels of it that show
// its surface (restir_neighbour_matches), made a reservoir this frame (with a trace decision: it
// traces) and hold a sample (a neighbour that found no visible light
// gives none: restir_di.py on visibility reuse), combined by generalized RIS with pairwise MIS of the
// unshadowed targets (restir_di.glsl): each target is evaluated at its own pixel's surface, so
// which neighbours pass the surface test changes the noise, not the mean. With RESTIR_SHARE_VIEWS a pixel of view
// v > 0 also takes view 0's reservoir where this surface point lies in view 0 (its view_proj; the
// same test), so the views of a frame share their samples; each view keeps its own target, MIS
// weights and shadow rays, so no light passes between them.
// The neighbours are drawn twice from one generator: first to test them (the canonical's share of
// each pair depends on how many pass), keeping a bit for each that passes, then to resample those;
// no array is kept, and each neighbour's surface is read once.
#include "restir_stage.glsl"

layout(rgba32ui) readonly uniform uimage2DArray reservoirs_in;
layout(rgba32ui) writeonly uniform uimage2DArray reservoirs_out;

// The pixel q of neighbour k (< RESTIR_SPATIAL_SAMPLES: drawn from u within the radius;
// RESTIR_SPATIAL_SAMPLES: view 0's pixel of this point) of pixel p at render-space `pos` and linear
// depth `depth`, and the linear depth q_depth its surface must have there (`depth`, or the point's
// in view 0); false when there is none.
bool restir_neighbour_pixel(ivec3 p, vec3 pos, float depth, int k, vec2 u, ivec3 size, out ivec3 q,
                            out float q_depth) {
    q_depth = depth;
    if (k < RESTIR_SPATIAL_SAMPLES) {
        float radius = RESTIR_SPATIAL_RADIUS * sqrt(u.x), angle = 2.0 * RAYVR_PI * u.y;
        q = p + ivec3(ivec2(round(radius * vec2(cos(angle), sin(angle)))), 0);
        return q.xy != p.xy;
    }
    vec4 clip = views[0].view_proj * vec4(pos, 1.0);
    q = ivec3(0);
    if (!(clip.w > 0.0)) return false;
    q = ivec3(ivec2(floor((clip.xy / clip.w * 0.5 + 0.5) * vec2(size.xy))), 0);
    q_depth = -(views[0].view * vec4(pos, 1.0)).z;
    return true;
}

// Whether neighbour k of pixel p (restir_neighbour_pixel; p's linear depth `depth`, normal n and
// effect word) shows p's surface and holds a sample; q its pixel.
bool restir_neighbour(ivec3 p, vec3 pos, float depth, vec3 n, uint word, int k, vec2 u, ivec3 size, out ivec3 q) {
    float q_depth_want;
    if (!restir_neighbour_pixel(p, pos, depth, k, u, size, q, q_depth_want)) return false;
    if (!pixel_inside(q.xy, size.xy)) return false;
#if TRACE_DECISION
    if (decision_reconstructed(q)) return false;   // it made no reservoir this frame
#endif
    if (!(reservoir_unpack(imageLoad(reservoirs_in, q)).weight > 0.0)) return false;
    return restir_neighbour_matches(q_depth_want, n, word, gbuf_fetch_posW(q).w, normalize(gbuf_fetch_normW(q).xyz),
                                    gbuf_fetch_effect(q));
}

void main() {
    ivec3 p;
    GSurface g;
    PathVertex s;
    ivec3 size = imageSize(reservoirs_out);
    if (!restir_pixel(size, p, g, s)) return;
    bool specular_traced = restir_specular_traced(g);
    float depth = gbuf_fetch_posW(p).w;
    uint word = gbuf_fetch_effect(p);
    Reservoir c = reservoir_unpack(imageLoad(reservoirs_in, p));
    int last = RESTIR_SPATIAL_SAMPLES - 1;
#if RESTIR_SHARE_VIEWS
    if (p.z > 0) last = RESTIR_SPATIAL_SAMPLES;
#endif
    Rng start = rng_init(uvec2(p.xy), view_global_index(uint(p.z)), frame_index(), RNG_SALT_RESTIR_SPATIAL);
    Rng rng = start;
    int found = 0;
    uint passed = 0u;   // bit k: neighbour k shows this surface and holds a sample
    ivec3 q;
    for (int k = 0; k <= last; ++k) {
        if (restir_neighbour(p, g.pos, depth, g.n, word, k, rng_next2(rng), size, q)) {
            ++found;
            passed |= 1u << uint(k);
        }
    }

    uvec2 c_id = reservoir_light_id(c);
    uint hints = restir_hints_at(p);
    float c_at_c = c.weight > 0.0 ? restir_target_of(s, specular_traced, hints, c_id) : 0.0;
    float c_share = c.confidence / float(max(found, 1));   // M_c / k: the canonical's part of each pair
    float c_mis = found == 0 ? c.confidence : 0.0;
    float confidence = c.confidence;
    ReservoirStream pick = stream_begin(rng_next(rng));
    rng = start;
    for (int k = 0; k <= last; ++k) {
        vec2 u = rng_next2(rng);
        float q_depth;
        if ((passed & (1u << uint(k))) == 0u) continue;
        restir_neighbour_pixel(p, g.pos, depth, k, u, size, q, q_depth);
        PathVertex s_q = path_vertex_at_gbuffer(gbuf_load(q), uint(q.z));
        Reservoir r = reservoir_unpack(imageLoad(reservoirs_in, q));
        uint q_hints = restir_hints_at(q);
        confidence += r.confidence;
        if (c_at_c > 0.0)
            c_mis += pair_weight(c_share, c_at_c, r.confidence, restir_target_of(s_q, specular_traced, q_hints, c_id));
        if (!(r.weight > 0.0)) continue;
        uvec2 id = reservoir_light_id(r);
        float c_at_r = restir_target_of(s, specular_traced, hints, id);
        float r_at_r = restir_target_of(s_q, specular_traced, q_hints, id);
        stream_add(pick, id, pair_weight(r.confidence, r_at_r, c_share, c_at_r) * c_at_r * r.weight, c_at_r);
    }
    stream_add(pick, c_id, c_mis * c_at_c * c.weight, c_at_c);
    imageStore(reservoirs_out, p, reservoir_pack(stream_reservoir(pick, confidence, confidence)));
}
