// Deferred probe lookups: what a ray pass's traversal kernel records at a path vertex so that a
// second dispatch, which traces no rays, looks the probes up (glsl/probe_gi.glsl) and adds their
// light. The lookup's registers in a kernel that also traverses the BVH cost the traversal its
// occupancy (the probe update measured 2.2x, a register probe of the path tracer 2.35x), so the
// traversal kernel only packs and stores 32 bytes per vertex.
//
//   ProbeRecord probe_record_at(PathVertex s, vec3 throughput, bool glossy)
//       the lookups of vertex s reached with `throughput`: its indirect diffuse light
//       (probe_gi_diffuse), and with `glossy` the glossy fallback of a path stopped there
//       (probe_gi_glossy)
//   ProbeRecord probe_record_none()         no lookup (the path ended before this vertex)
//   uvec4 probe_record_hit(r), probe_record_factors(r)     the record's two rgba32ui texels
//   ProbeRecord probe_record_unpack(uvec4 hit, uvec4 factors)
//   vec3 probe_record_radiance(ProbeRecord r)   the radiance it adds (0 unless PROBE_GI is 1)
//   int probe_record_layer(int view, int bounce, int views)   its layer in the record arrays
//
// Texels (rgba32ui, one layer per view and bounce):
//   hit      x, y, z: the position's float bits (render space), w: the shading normal n (octahedral,
//            snorm16 x2)
//   factors  x: v, unit direction towards the previous vertex (octahedral, snorm16 x2);
//            y, z, w: float16 pairs (diffuse.r, diffuse.g) (diffuse.b, glossy.r) (glossy.g, glossy.b)
// `diffuse` is throughput x diffuse albedo, `glossy` throughput x specular albedo (0: no glossy
// fallback); both 0: no lookup. The result equals the in-kernel lookup's within the float16
// rounding of the factors and the 16-bit octahedral rounding of n and v.
#pragma once
#include "probe_gi.glsl"
#include "color.glsl"

struct ProbeRecord {
    vec3 pos;       // render space
    vec3 n;         // shading normal, facing v
    vec3 v;         // towards the previous vertex
    vec3 diffuse;   // throughput x diffuse albedo (probe_gi_diffuse's weight times pi)
    vec3 glossy;    // throughput x specular albedo (probe_gi_glossy's), 0 where the path goes on
};

ProbeRecord probe_record_none() {
    ProbeRecord r;
    r.pos = vec3(0.0);
    r.n = vec3(0.0, 0.0, 1.0);
    r.v = vec3(0.0, 0.0, 1.0);
    r.diffuse = vec3(0.0);
    r.glossy = vec3(0.0);
    return r;
}

ProbeRecord probe_record_at(PathVertex s, vec3 throughput, bool glossy) {
    vec3 diffuse, specular, transmitted;   // the glossy fallback lights what the surface reflects
    bsdf_albedo_parts(s.bsdf, s.n, s.v, diffuse, specular, transmitted);
    ProbeRecord r;
    r.pos = s.pos;
    r.n = s.n;
    r.v = s.v;
    r.diffuse = throughput * diffuse;
    r.glossy = glossy ? throughput * specular : vec3(0.0);
    return r;
}

uvec4 probe_record_hit(ProbeRecord r) { return uvec4(floatBitsToUint(r.pos), oct_pack_snorm16(r.n)); }

uvec4 probe_record_factors(ProbeRecord r) {
    // non-finite factors are kept (the lookup side scrubs and counts them); finite ones clamp
    // into float16's range
    vec3 d = is_finite(r.diffuse) ? to_half_range(r.diffuse) : r.diffuse;
    vec3 g = is_finite(r.glossy) ? to_half_range(r.glossy) : r.glossy;
    return uvec4(oct_pack_snorm16(r.v), packHalf2x16(d.rg), packHalf2x16(vec2(d.b, g.r)), packHalf2x16(g.gb));
}

ProbeRecord probe_record_unpack(uvec4 hit, uvec4 factors) {
    ProbeRecord r;
    r.pos = uintBitsToFloat(hit.xyz);
    r.n = oct_unpack_snorm16(hit.w);
    r.v = oct_unpack_snorm16(factors.x);
    vec2 a = unpackHalf2x16(factors.y), b = unpackHalf2x16(factors.z), c = unpackHalf2x16(factors.w);
    r.diffuse = vec3(a, b.x);
    r.glossy = vec3(b.y, c);
    return r;
}

int probe_record_layer(int view, int bounce, int views) { return bounce * views + view; }

vec3 probe_record_radiance(ProbeRecord r) {
    vec3 l = vec3(0.0);
#if PROBE_GI
    // the same lookups as probe_gi_diffuse and probe_gi_glossy (glsl/probe_gi.glsl)
    if (any(notEqual(r.diffuse, vec3(0.0))))
        l += r.diffuse * probe_gi_irradiance(r.pos, r.n, r.v) * (1.0 / RAYVR_PI);
    if (any(notEqual(r.glossy, vec3(0.0))))
        l += r.glossy * probe_gi_irradiance(r.pos, reflect(-r.v, r.n), r.v) * (1.0 / RAYVR_PI);
#endif
    return l;
}
