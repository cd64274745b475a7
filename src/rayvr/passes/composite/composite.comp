// Hybrid composite: per pixel, the lighting its effect asked for. RASTER pixels keep the unshadowed
// direct light; SHADOWS and above take the ray-traced shadowed light; REFLECTIONS and above add
// the reflected radiance (already weighted by the specular BSDF); PATH_TRACED pixels take the
// path tracer's (accumulated) radiance when the graph has one.
// With SPLIT_LOBES the same light is also written as the two lobes a denoiser demodulates apart
// (rayvr.passes.SVGF), emission excluded: `dst_diffuse` the direct (shadowed) light, or the path
// tracer's diffuse part, and the background where nothing was drawn; `dst_specular` the
// reflections, or the path tracer's specular part. (Direct light's specular highlights stay in
// the diffuse lobe: the lighting passes return them summed.)
// With PROBE_GI the probes' indirect diffuse light of the G-buffer surface is added here for
// RASTER, SHADOWS and REFLECTIONS pixels (to the diffuse lobe with SPLIT_LOBES), and for RASTER
// and SHADOWS pixels, whose reflections are not traced, their glossy light about the lobe's
// dominant direction (probe_gi_diffuse_glossy; to the specular lobe): a metal is no longer black.
// This pass traces no rays, so the lookup's registers cost no BVH traversal its occupancy, as
// they did in RTShadows (the probe update measured 2.2x from the same split).
// With TRACE_DECISION a pixel the decision flags DECISION_SPREAD (SVGF gives it another view's
// filtered light) is left: 0 in `dst`, and the two lobes unwritten (SVGF, their one reader, reads
// neither at such a pixel). With WORK_TILES_INPUT the workgroups are the decision's work tiles
// (glsl/work_tiles.glsl), and the pass clears `dst` before, for the spread pixels of the others.
#define GBUF_READER 1
#include "gbuffer.glsl"
#include "trace_decision.glsl"
#include "probe_gi.glsl"
#include "ray_group.glsl"

// HybridComposite's workgroups: with PROBE_GI one warp (8x4 pixels; in a camera grid 4x2 pixels of 4 views,
// whose lookups share probes), else 8x8 pixels of one view
layout(local_size_x = RAY_GROUP_SIZE) in;

uniform sampler2DArray direct_tex;
#if HAS_SHADOWS
uniform sampler2DArray shadowed_tex;
#endif
#if HAS_REFLECTIONS
uniform sampler2DArray reflection_tex;
#endif
#if HAS_PATHS
uniform sampler2DArray path_tex;
#endif
layout(rgba16f) writeonly uniform image2DArray dst;
#if SPLIT_LOBES
#if HAS_PATH_LOBES
uniform sampler2DArray path_diffuse_tex;
uniform sampler2DArray path_specular_tex;
#endif
layout(rgba16f) writeonly uniform image2DArray dst_diffuse;
layout(rgba16f) writeonly uniform image2DArray dst_specular;
#endif

void main() {
    ivec3 p = ray_group_pixel();
    if (any(greaterThanEqual(p, imageSize(dst)))) return;   // past the image or the last view
#if TRACE_DECISION
    if (decision_spread(decision_at(p))) {   // the lobes are left unwritten: SVGF reads neither there
        imageStore(dst, p, vec4(0.0));   // as the clear before a dispatch over the work tiles
        return;
    }
#endif
    uint effect = gbuf_effect_at(p);
    vec3 c = texelFetch(direct_tex, p, 0).rgb;
    vec3 reflected = vec3(0.0);
    if (effect != GBUF_NO_GEOMETRY) {
#if HAS_SHADOWS
        if (effect >= EFFECT_SHADOWS) c = texelFetch(shadowed_tex, p, 0).rgb;
#endif
#if HAS_REFLECTIONS
        if (effect >= EFFECT_REFLECTIONS) reflected = texelFetch(reflection_tex, p, 0).rgb;
#endif
#if PROBE_GI
        if (effect < EFFECT_PATH_TRACED) {
            PathVertex s = path_vertex_at_gbuffer(gbuf_load(p), uint(p.z));
            if (effect < EFFECT_REFLECTIONS) {   // untraced reflections: the probes' glossy light
                vec3 glossy;
                c += finite_or_zero(probe_gi_diffuse_glossy(s, glossy));
                reflected = finite_or_zero(glossy);
            } else {
                c += finite_or_zero(probe_gi_diffuse(s));
            }
        }
#endif
    }
#if SPLIT_LOBES
    vec3 diffuse = effect == GBUF_NO_GEOMETRY ? c : max(c - gbuf_fetch_emissive(p).rgb, 0.0);
    vec3 specular = reflected;
#if HAS_PATH_LOBES
    if (effect == EFFECT_PATH_TRACED) {
        diffuse = texelFetch(path_diffuse_tex, p, 0).rgb;
        specular = texelFetch(path_specular_tex, p, 0).rgb;
    }
#endif
    imageStore(dst_diffuse, p, vec4(to_half_range(diffuse), 1.0));
    imageStore(dst_specular, p, vec4(to_half_range(specular), 1.0));
#endif
    c += reflected;
#if HAS_PATHS
    if (effect == EFFECT_PATH_TRACED) c = texelFetch(path_tex, p, 0).rgb;
#endif
    imageStore(dst, p, vec4(to_half_range(c), 1.0));
}
