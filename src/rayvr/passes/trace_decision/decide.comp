// TraceDecision: per pixel of every view, whether it traces its rays this frame or takes its light
// from a traced pixel (glsl/trace_decision.glsl has the texel's layout; the pass's docstring the
// rules). Defines:
//   REUSE 1: views reuse the shaded samples of source views: REUSE_COLS views a grid row (view v
//     at column v % REUSE_COLS, row v / REUSE_COLS), sources every REUSE_STRIDE-th row and column;
//     two views: the first eye (REUSE_ALTERNATE: the eye of the frame's parity); surfaces without
//     transmission whose roughness >= REUSE_MIN_ROUGHNESS, or whose lobe is wide against the eyes'
//     parallax (REUSE_LOBE_FRACTION: view_independent)
//   FOVEATION 1 (fixed: the image's centre) or 2 (gaze: the eye tracker's, else the centre): a pixel
//     traces with probability budget(e) (FOVEAL_RADIUS degrees, PERIPHERY_SHARE), an 8x8 ordered
//     dither whose ranks the frame index rotates through, so a pixel's turns are spread over frames
//   SHARE_LIGHT_SAMPLES 1 (with REUSE): a pixel of effect SHADOWS or REFLECTIONS that traces for
//     its lobe but finds the same surface in a source view is flagged DECISION_SHARED_LIGHT there
//     (RTShadows shades it over that pixel's light sample)
//   REUSE_SPREAD 1: a pixel whose light is another view's is flagged DECISION_SPREAD (SVGF spreads
//     the source's filtered light to it; the fills and the composite leave it)
//   WORK_TILES_APPEND 1 (with REUSE_SPREAD): lists the 8x4 tiles that hold a pixel whose light is
//     not spread (glsl/work_tiles.glsl), the tiles the ray passes and the composite run over
//   EVERY_SURFACE 1: every drawn pixel has rays to trace (a path tracer from the camera; the sky
//     traces too), else those of effect SHADOWS and above
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "scene.glsl"
#include "same_surface.glsl"
#include "trace_decision.glsl"
#include "work_tiles.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;   // two work tiles (work_tiles_append)
layout(rg32ui) writeonly uniform uimage2DArray dst;

// Candidates around a projected point or a pixel, nearest first (radius 2).
const int TAPS = 25;
const ivec2 TAP[25] = ivec2[](
    ivec2(0, 0), ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1), ivec2(1, 1), ivec2(-1, 1), ivec2(1, -1),
    ivec2(-1, -1), ivec2(2, 0), ivec2(-2, 0), ivec2(0, 2), ivec2(0, -2), ivec2(2, 1), ivec2(2, -1), ivec2(-2, 1),
    ivec2(-2, -1), ivec2(1, 2), ivec2(-1, 2), ivec2(1, -2), ivec2(-1, -2), ivec2(2, 2), ivec2(-2, 2), ivec2(2, -2),
    ivec2(-2, -2));
// same_surface()'s reach: the texel a point projects to lies within NEAR_PIXELS of it; a neighbour
// up to 2 pixels away within FAR_PIXELS.
const float NEAR_PIXELS = 1.5;
const float FAR_PIXELS = 3.0;

bool inside(ivec3 q) { return all(greaterThanEqual(q.xy, ivec2(0))) && all(lessThan(q.xy, ivec2(views[q.z].clip.zw))); }

// -- the ray budget ------------------------------------------------------------------------------
#if FOVEATION
vec2 image_tangents(uint v, vec2 pixel) {
    vec4 t = views[v].fov_tan;
    vec2 uv = pixel / views[v].clip.zw;
    return vec2(mix(t.x, t.y, uv.x), mix(t.z, t.w, uv.y));
}

vec2 gaze_tangents(uint v) {
#if FOVEATION == 2
    if (views[v].gaze.z > 0.5) return views[v].gaze.xy;
#endif
    vec4 t = views[v].fov_tan;
    return vec2(0.5 * (t.x + t.y), 0.5 * (t.z + t.w));
}

float eccentricity_deg(uint v, vec2 pixel) {
    vec3 a = normalize(vec3(image_tangents(v, pixel), -1.0));
    vec3 g = normalize(vec3(gaze_tangents(v), -1.0));
    return degrees(atan(length(cross(a, g)), dot(a, g)));   // exact near 0, unlike acos
}

float budget_at(ivec3 q) {
    float e = eccentricity_deg(uint(q.z), vec2(q.xy) + 0.5);
    float r = float(FOVEAL_RADIUS);
    return e <= r ? 1.0 : PERIPHERY_SHARE + (1.0 - PERIPHERY_SHARE) * (r / e) * (r / e);
}

// Rank of pixel q in the 8x8 Bayer matrix: the bits of (x ^ y, y) interleaved and reversed.
uint bayer8(ivec2 q) {
    uint x = uint(q.x) & 7u, y = uint(q.y) & 7u, a = x ^ y;
    return ((a & 1u) << 5u) | ((y & 1u) << 4u) | ((a & 2u) << 2u) | ((y & 2u) << 1u) | ((a & 4u) >> 1u)
           | ((y & 4u) >> 2u);
}

// Whether pixel q's turn to trace falls on this frame: its dither rank shifted by the frame's
// van der Corput step (of 64), below its budget's share of the ranks.
bool selected(ivec3 q, float budget) {
    uint shift = bitfieldReverse(frame_index() & 63u) >> 26u;
    return float((bayer8(q.xy) + shift) & 63u) + 0.5 < budget * 64.0;
}
bool selected(ivec3 q) { return selected(q, budget_at(q)); }
#else
float budget_at(ivec3 q) { return 1.0; }
bool selected(ivec3 q, float budget) { return true; }
bool selected(ivec3 q) { return true; }
#endif

// -- reuse between views ----------------------------------------------------------------------------
#if REUSE
// Light refracts through the material: what another eye sees through it is another path.
bool refracts(uint material) { return material_factors(material).transmission > 0.0; }

// A lobe that looks alike from view v's eye and source s's: no refraction, and rough enough
// (roughness >= REUSE_MIN_ROUGHNESS), or the angle between the two eyes seen from the point `pos`
// below REUSE_LOBE_FRACTION of the GGX lobe's width (alpha = roughness^2 radians): a far glossy
// surface looks the same to both eyes, a near one does not.
// With REUSE_DELTA_LOBES a delta lobe at a pixel whose reflections are not traced (effect below
// REFLECTIONS) is reused too: light samples give it nothing, and the probes' glossy light about
// its mirror direction is irradiance, smooth in direction.
bool view_independent(float roughness, uint material, uint effect, vec3 pos, uint v, uint s) {
    if (refracts(material)) return false;
    if (roughness >= REUSE_MIN_ROUGHNESS) return true;
    if (REUSE_DELTA_LOBES != 0 && effect < EFFECT_REFLECTIONS && roughness < MATERIAL_DELTA_ROUGHNESS) return true;
    vec3 a = views[v].eye.xyz - pos, b = views[s].eye.xyz - pos;
    float parallax = atan(length(cross(a, b)), dot(a, b));
    return parallax < float(REUSE_LOBE_FRACTION) * roughness * roughness;
}

bool is_source(uint v) {
    if (view_count() == 2u) return v == (REUSE_ALTERNATE != 0 ? frame_index() & 1u : 0u);
    uint col = v % uint(REUSE_COLS), row = v / uint(REUSE_COLS);
    return col % uint(REUSE_STRIDE) == 0u && row % uint(REUSE_STRIDE) == 0u;
}

// The source views nearest view v (not a source): the other eye, or in a grid the sources at the
// corners of its cell on either side (one where the grid ends). Returns how many.
int sources_of(uint v, out uint s0, out uint s1) {
    if (view_count() == 2u) {
        s0 = s1 = 1u - v;
        return 1;
    }
    uint cols = uint(REUSE_COLS), rows = (view_count() + cols - 1u) / cols, stride = uint(REUSE_STRIDE);
    uint col = v % cols, row = v / cols;
    uint c0 = col - col % stride, r0 = row - row % stride;
    uint c1 = col % stride == 0u || c0 + stride >= cols ? c0 : c0 + stride;
    uint r1 = row % stride == 0u || r0 + stride >= rows ? r0 : r0 + stride;
    s0 = r0 * cols + c0;
    s1 = r1 * cols + c1;
    return s1 < view_count() && s1 != s0 ? 2 : 1;
}

// Where g's point lies in source view s, when the pixel it projects to shows the same surface
// (else the point is hidden there, or off its image: DECISION_NONE): DECISION_REUSE at that
// position (the fill interpolates the traced pixels of the surface about it). With foveation the
// pixel may not trace this frame: then the nearest that does, of the same surface within 2 pixels,
// stands in (DECISION_FILL at its centre), or none does (DECISION_NONE).
uint reuse_from(GSurface g, uint v, uint s, out vec2 at) {
    vec4 clip = views[s].view_proj * vec4(g.pos, 1.0);
    // the source's pixels sample at their centres plus the views' jitter
    at = (clip.xy / clip.w * 0.5 + 0.5) * views[s].clip.zw - views[s].jitter.xy;
    ivec3 q0 = ivec3(ivec2(floor(at)), int(s));
    if (!(clip.w > 0.0) || !inside(q0) || !same_surface(g, v, q0, NEAR_PIXELS)) return DECISION_NONE;
    if (selected(q0)) return DECISION_REUSE;
    for (int k = 1; k < TAPS; ++k) {
        ivec3 q = q0 + ivec3(TAP[k], 0);
        if (inside(q) && selected(q) && same_surface(g, v, q, FAR_PIXELS)) {
            at = vec2(q.xy) + 0.5;
            return DECISION_FILL;
        }
    }
    return DECISION_NONE;
}
#endif

// -- the decision -----------------------------------------------------------------------------------
// The kind of pixel p (surface g) and its source: view `view`, position `at` (pixels).
uint decide(ivec3 p, GSurface g, float budget, out uint view, out vec2 at) {
    uint v = uint(p.z);
    view = v;
    at = vec2(p.xy) + 0.5;
#if REUSE
    bool reuses = !is_source(v);
    uint s[2];
    int n = reuses ? sources_of(v, s[0], s[1]) : 0;
    bool independent = reuses && view_independent(g.roughness, g.material, g.effect, g.pos, v, s[0]);
    // a glossy lobe traces, but its direct light sample may be a source pixel's: shared_view then
    // (glass too: what the eyes see through it differs, but its point's light sample and shadow ray
    // do not, and its lobes are shaded its own)
    bool shares = SHARE_LIGHT_SAMPLES != 0 && reuses && !independent && g.effect >= EFFECT_SHADOWS
                  && g.effect <= EFFECT_REFLECTIONS;
    uint shared_view = v;
    vec2 shared_at = at;
    if (independent || shares) {
        for (int i = 0; i < n; ++i) {
            vec2 found;
            uint kind = reuse_from(g, v, s[i], found);
            if (kind == DECISION_NONE) continue;
            if (independent) {
                view = s[i];
                at = found;
                return kind;
            }
            shared_view = s[i];   // the traced pixel at `found` shows this surface: its centre
            shared_at = floor(found) + 0.5;
            break;
        }
        // disoccluded, or the source's surface differs: traced, never filled
        if (independent) return DECISION_TRACE;
    }
#endif
#if FOVEATION
    if (!selected(p, budget)) {
        // a neighbour that certainly traces: its turn, and in a view that reuses a lobe that cannot
        for (int k = 1; k < TAPS; ++k) {
            ivec3 q = p + ivec3(TAP[k], 0);
            if (!inside(q) || !selected(q) || !same_surface(g, v, q, FAR_PIXELS)) continue;
#if REUSE
            if (reuses && view_independent(gbuf_fetch_metalRough(q).y, g.material, g.effect, g.pos, v, s[0])) continue;
#endif
            at = vec2(q.xy) + 0.5;
            return DECISION_FILL;
        }
    }
#endif
#if REUSE
    if (shared_view != v) {
        view = shared_view;
        at = shared_at;
        return DECISION_TRACE | DECISION_SHARED_LIGHT;
    }
#endif
    return DECISION_TRACE;
}

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    bool own_light = false;   // inside, and its light is not another view's
    if (all(lessThan(p, imageSize(dst)))) {
        float budget = budget_at(p);
        uint effect = gbuf_effect_at(p);
        uint kind = DECISION_NONE, view = uint(p.z);
        vec2 at = vec2(p.xy) + 0.5;
        if (effect == GBUF_NO_GEOMETRY) {
            kind = EVERY_SURFACE != 0 ? DECISION_TRACE : DECISION_NONE;
        } else if (EVERY_SURFACE != 0 || effect >= EFFECT_SHADOWS) {
            kind = decide(p, gbuf_load(p), budget, view, at);
        }
#if REUSE_SPREAD
        if (kind == DECISION_REUSE || (kind == DECISION_FILL && int(view) != p.z)) kind |= DECISION_SPREAD;
#endif
        own_light = (kind & DECISION_SPREAD) == 0u;
        imageStore(dst, p, uvec4(decision_pack(kind, budget, view, at), 0u, 0u));
    }
#if WORK_TILES_APPEND
    work_tiles_append(own_light);
#endif
}
