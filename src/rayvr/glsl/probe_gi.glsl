// Indirect diffuse light from irradiance probes (DDGI, Majercik et al. 2019), updated once per
// frame by rayvr.passes.ProbeGI and read by every view's shading at texture cost.
//
//   vec3 probe_gi_irradiance(vec3 p, vec3 n, vec3 v)  irradiance (integral of incident radiance
//       x cos over n's hemisphere) of light that scattered at least once, at render-space point p
//       with unit normal n; v: unit direction towards the viewer (moves the lookup off the surface)
//   vec3 probe_gi_diffuse(PathVertex s)   diffuse albedo x irradiance / pi: the indirect diffuse
//       radiance leaving s towards s.v
//   vec3 probe_gi_glossy(PathVertex s)    reflected albedo x irradiance about the mirror direction
//       / pi: the glossy fallback for a reflection path that stops at s (glass's transmitted
//       share is left out there, as in probe_records.glsl's deferred lookup)
//   vec3 probe_gi_diffuse_glossy(PathVertex s, out vec3 glossy)   both from one lookup: the
//       composite's indirect light for pixels whose reflections are not traced (the glossy part
//       about the lobe's dominant direction, probe_gi_glossy_direction; glass's transmitted share
//       from a second lookup behind the surface)
//
// Both return 0 unless PROBE_GI is 1; then the shader declares the samplers probe_irradiance_tex
// (rgba16f, the update reads its float32 history instead; alpha: 1 where the probe is active, 0
// where it is disabled inside geometry) and probe_depth_tex (rg32f: mean distance, mean squared
// distance), 2D arrays of one layer sampled linearly, clamped to their edges, and the storage
// block ProbeVolumes (layout in rayvr/passes/probe_gi/layout.py).
//
// The 8 probes around p are weighted trilinearly, by how much they face the surface, and by
// Chebyshev's bound on the probe seeing p (its depth moments): a probe behind a wall sees the wall
// nearer than p and drops out, so light does not leak through. Disabled probes (inside geometry)
// drop out too.
#pragma once
#include "path_vertex.glsl"
#include "octahedral.glsl"
#include "lights.glsl"   // environment_radiance: the sky a delta lobe sees

#ifndef PROBE_GI
#define PROBE_GI 0
#endif

#define PROBE_IRRADIANCE_TILE 8   // texels per side of a probe's tile, one-texel border included
#define PROBE_DEPTH_TILE 16
#define PROBE_MISS_DEPTH 2.0   // escaped rays' recorded distance, in depth limits (vol.lo.w); hits stop at 1
#define PROBE_FLAG_VISIBILITY 1u

#if PROBE_GI
#include "probe_volume_record.glsl"   // ProbeVolume
layout(std430) readonly buffer ProbeVolumes {
    uvec4 probe_info;   // x: volumes, y: tiles per atlas row, z: probes in all, w: flags
    ProbeVolume probe_volumes[];
};
uniform sampler2DArray probe_irradiance_tex;
uniform sampler2DArray probe_depth_tex;

ivec2 probe_tile(uint probe) { return ivec2(probe % probe_info.y, probe / probe_info.y); }

// The first volume whose box holds p (list the fine ones first), else the last (clamped to it).
uint probe_volume_at(vec3 p) {
    uint n = probe_info.x;
    for (uint i = 0u; i + 1u < n; ++i) {
        if (all(greaterThanEqual(p, probe_volumes[i].lo.xyz)) && all(lessThanEqual(p, probe_volumes[i].hi.xyz)))
            return i;
    }
    return n - 1u;
}

// Texture coordinates of direction d in probe `probe`'s tile of an atlas of `tile`-texel tiles.
vec3 probe_tile_uv(sampler2DArray atlas, uint probe, vec3 d, int tile) {
    vec2 texel = vec2(probe_tile(probe) * tile) + 1.0 + (oct_encode(d) * 0.5 + 0.5) * float(tile - 2);
    return vec3(texel / vec2(textureSize(atlas, 0).xy), 0.0);
}

// Chebyshev's bound on a probe's depth reaching d that way, from its depth moments m (mean, mean
// of squares): 1 up to the mean distance.
float probe_chebyshev(vec2 m, float d) {
    if (d <= m.x) return 1.0;
    float variance = abs(m.y - m.x * m.x);
    float beyond = d - m.x;
    return variance / (variance + beyond * beyond);
}

// The irradiance about n at p, and with `both` also about direction r (`along_r`) from the same
// probes and weights: one more fetch per probe, not a second lookup. With `sky`, `sky_r` is the
// share of the probes' rays along r that leave the scene: escaped rays record PROBE_MISS_DEPTH
// times the depth limit (hits at most the limit), and probe_chebyshev there is that share where
// the rays either escape or stop at one distance (an upper bound otherwise), blended with the same
// weights; another fetch per probe; 0 without depth visibility.
vec3 probe_gi_irradiance_at(vec3 p, vec3 n, vec3 v, const bool both, vec3 r, out vec3 along_r,
                            const bool sky, out float sky_r) {
    along_r = vec3(0.0);
    sky_r = 0.0;
    if (probe_info.x == 0u) return vec3(0.0);
    ProbeVolume vol = probe_volumes[probe_volume_at(p)];
    bool visibility = (probe_info.w & PROBE_FLAG_VISIBILITY) != 0u;
    vec3 biased = p + n * vol.origin.w + v * vol.spacing.w;
    ivec3 last = ivec3(vol.counts.xyz) - 1;
    vec3 g = (biased - vol.origin.xyz) / vol.spacing.xyz;
    ivec3 base = clamp(ivec3(floor(g)), ivec3(0), max(last - 1, ivec3(0)));
    vec3 alpha = clamp(g - vec3(base), 0.0, 1.0);
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int i = 0; i < 8; ++i) {
        ivec3 offset = ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        ivec3 cell = min(base + offset, last);
        uint probe = vol.counts.w + uint(cell.x) + vol.counts.x * (uint(cell.y) + vol.counts.y * uint(cell.z));
        vec3 at = vol.origin.xyz + vec3(cell) * vol.spacing.xyz;
        vec3 tri = mix(1.0 - alpha, alpha, vec3(offset));
        // Probes behind the surface count less (smoothly, so the weights never all vanish).
        float facing = (dot(normalize(at - p), n) + 1.0) * 0.5;
        float w = facing * facing + 0.2;
        if (visibility) {
            vec3 from_probe = biased - at;
            float d = length(from_probe);
            vec2 m = texture(probe_depth_tex, probe_tile_uv(probe_depth_tex, probe, d > 0.0 ? from_probe / d : n,
                                                            PROBE_DEPTH_TILE)).xy;
            float chebyshev = probe_chebyshev(m, d);   // farther than the mean distance that way
            w *= chebyshev * chebyshev * chebyshev;
        }
        w = max(w, 1e-6);
        const float crush = 0.2;   // tiny weights to nearly nothing: no faint light behind walls
        if (w < crush) w *= w * w / (crush * crush);
        vec4 e = texture(probe_irradiance_tex, probe_tile_uv(probe_irradiance_tex, probe, n, PROBE_IRRADIANCE_TILE));
        w *= tri.x * tri.y * tri.z * e.a;   // alpha 0: a disabled probe drops out
        sum += w * e.rgb;
        if (both)
            along_r += w * texture(probe_irradiance_tex, probe_tile_uv(probe_irradiance_tex, probe, r,
                                                                       PROBE_IRRADIANCE_TILE)).rgb;
        if (sky && visibility)
            sky_r += w * probe_chebyshev(texture(probe_depth_tex, probe_tile_uv(probe_depth_tex, probe, r,
                                                                                PROBE_DEPTH_TILE)).xy,
                                         vol.lo.w * PROBE_MISS_DEPTH * 0.999);
        total += w;
    }
    along_r = total > 0.0 ? along_r / total : vec3(0.0);
    sky_r = total > 0.0 ? sky_r / total : 0.0;
    return total > 0.0 ? sum / total : vec3(0.0);
}

vec3 probe_gi_irradiance(vec3 p, vec3 n, vec3 v) {
    vec3 unused;
    float no_sky;
    return probe_gi_irradiance_at(p, n, v, false, n, unused, false, no_sky);
}
#endif

#if PROBE_GI
// Diffuse albedo `diffuse` x the irradiance about s's normal / pi.
vec3 probe_gi_diffuse_of(PathVertex s, vec3 diffuse) {
    return diffuse * probe_gi_irradiance(s.pos, s.n, s.v) * (1.0 / RAYVR_PI);
}

// What a delta lobe (no light sample reaches it) gets of the environment along `dir`, seen by the
// probes as the share `sky` of their rays escaping that way; 0 for any other lobe.
vec3 probe_gi_sky(bool delta, vec3 dir, float sky) {
    return delta ? environment_radiance(dir) * sky : vec3(0.0);
}
#endif

vec3 probe_gi_diffuse(PathVertex s) {
#if PROBE_GI
    vec3 diffuse, specular;
    bsdf_albedo(s.bsdf, s.n, s.v, diffuse, specular);
    return probe_gi_diffuse_of(s, diffuse);
#else
    return vec3(0.0);
#endif
}

// The direction about which a GGX lobe of perceptual `roughness` gathers most of its light (the
// specular dominant direction of Lagarde and de Rousiers 2014): the mirror direction for a smooth
// surface, bending to the normal n as the lobe widens.
float probe_gi_lobe_bend(float roughness) {
    float a = roughness * roughness;
    return (1.0 - a) * (sqrt(1.0 - a) + a);
}

vec3 probe_gi_glossy_direction(vec3 n, vec3 v, float roughness) {
    return normalize(mix(n, reflect(-v, n), probe_gi_lobe_bend(roughness)));
}

// The direction about which a transmission lobe gathers most of its light, by analogy with
// probe_gi_glossy_direction: straight through (-v, as a thin sheet; the probes' irradiance is too
// smooth for a refracted image to matter) for a smooth surface, bending to -n as the lobe widens.
vec3 probe_gi_transmitted_direction(vec3 n, vec3 v, float roughness) {
    return -normalize(mix(n, v, probe_gi_lobe_bend(roughness)));
}

#if PROBE_GI
// `transmitted` (the surface's transmitted albedo) x the irradiance behind s about
// probe_gi_transmitted_direction / pi: a lookup from a point moved past the surface, made only
// where the surface transmits.
vec3 probe_gi_behind(PathVertex s, vec3 transmitted) {
    if (all(equal(transmitted, vec3(0.0)))) return vec3(0.0);
    vec3 t = probe_gi_transmitted_direction(s.n, s.v, s.bsdf.roughness);
    vec3 unused;
    float sky;
    bool delta = bsdf_is_delta(s.bsdf);
    vec3 e = probe_gi_irradiance_at(s.pos, t, -s.v, false, t, unused, delta, sky);
    return transmitted * (e * (1.0 / RAYVR_PI) + probe_gi_sky(delta, t, sky));
}

// probe_gi_diffuse's light + what a transmitting surface passes from behind (probe_gi_behind):
// the light a probe ray's hit sends back, so that glass does not darken the probes around it.
vec3 probe_gi_diffuse_transmitted(PathVertex s) {
    vec3 diffuse, specular, transmitted;
    bsdf_albedo_parts(s.bsdf, s.n, s.v, diffuse, specular, transmitted);
    return probe_gi_diffuse_of(s, diffuse) + probe_gi_behind(s, transmitted);
}
#endif

// Both at once, from one lookup: probe_gi_diffuse's value, and in `glossy` the reflected albedo x
// irradiance about the lobe's dominant direction / pi (a surface whose reflections are not traced:
// RASTER and SHADOWS pixels). Where that direction is within ~10 degrees of the normal (rough
// surfaces) the normal's irradiance serves both: irradiance is cosine-smoothed, and the second
// fetch per probe costs a third of the composite's lookup. A transmitting surface adds its
// transmitted albedo x the irradiance behind it about probe_gi_transmitted_direction / pi (a lookup
// of its own, from a point moved past the surface), so untraced glass shows the light behind it
// (blurred, without the emitters seen straight through; the environment only through a delta
// lobe, as far as the probes see it) instead of black.
vec3 probe_gi_diffuse_glossy(PathVertex s, out vec3 glossy) {
    glossy = vec3(0.0);
#if PROBE_GI
    vec3 diffuse, specular, transmitted, e_r;
    bsdf_albedo_parts(s.bsdf, s.n, s.v, diffuse, specular, transmitted);
    vec3 d = probe_gi_glossy_direction(s.n, s.v, s.bsdf.roughness);
    bool apart = dot(d, s.n) < 0.985;
    bool delta = bsdf_is_delta(s.bsdf);   // no light sample reaches it: the sky comes from here
    float sky;
    vec3 e_n = probe_gi_irradiance_at(s.pos, s.n, s.v, apart, d, e_r, delta, sky);
    glossy = specular * ((apart ? e_r : e_n) * (1.0 / RAYVR_PI) + probe_gi_sky(delta, d, sky));
    glossy += probe_gi_behind(s, transmitted);
    return diffuse * e_n * (1.0 / RAYVR_PI);
#else
    return vec3(0.0);
#endif
}

vec3 probe_gi_glossy(PathVertex s) {
#if PROBE_GI
    vec3 diffuse, reflected, transmitted;   // a transmission's light comes from behind: not from here
    bsdf_albedo_parts(s.bsdf, s.n, s.v, diffuse, reflected, transmitted);
    return reflected * probe_gi_irradiance(s.pos, reflect(-s.v, s.n), s.v) * (1.0 / RAYVR_PI);
#else
    return vec3(0.0);
#endif
}
