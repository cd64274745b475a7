// What the four stages of a probe update (probe_trace.comp, probe_shade.comp, probe_shadow.comp,
// probe_update.comp) share: the probe rays' directions and origins, and the ProbeRay record each
// stage hands on to the next (binding by name: the pass binds the block "ProbeRays" to its
// internal `rays` buffer, probes x rays records). Each stage is a workgroup per probe and an
// invocation per ray.
#pragma once
#include "probe_gi.glsl"

uniform mat3 probe_rotation;   // this update's random rotation of the ray set

const float PROBE_BACKFACE_DEPTH = 0.2;   // back-face hits count this near: Chebyshev hides the probe
const float PROBE_RAY_SPREAD = sqrt(4.0 * RAYVR_PI / float(PROBE_RAYS));   // a ray's share of the sphere (ray cones)
#define PROBE_RAY_MISS 0u
#define PROBE_RAY_SURFACE 1u
#define PROBE_RAY_BACKFACE 2u

#include "probe_ray_record.glsl"   // ProbeRay
layout(std430) buffer ProbeRays { ProbeRay probe_rays[]; };

// Direction i of n on the spherical Fibonacci lattice (equal areas).
vec3 spherical_fibonacci(uint i, uint n) {
    const float golden = 1.61803398874989484820;
    float z = 1.0 - (2.0 * float(i) + 1.0) / float(n);
    float phi = 2.0 * RAYVR_PI * fract(float(i) / golden);
    float r = sqrt(max(0.0, 1.0 - z * z));
    return vec3(r * cos(phi), r * sin(phi), z);
}

vec3 probe_ray_direction(uint ray) { return normalize(probe_rotation * spherical_fibonacci(ray, uint(PROBE_RAYS))); }

uint probe_volume_of(uint probe) {
    uint v = 0u;
    while (v + 1u < probe_info.x && probe >= probe_volumes[v + 1u].counts.w) ++v;
    return v;
}

// Render-space position of `probe` of volume `vol`.
vec3 probe_position(ProbeVolume vol, uint probe) {
    uint local = probe - vol.counts.w;
    uvec3 cell = uvec3(local % vol.counts.x, (local / vol.counts.x) % vol.counts.y,
                       local / (vol.counts.x * vol.counts.y));
    return vol.origin.xyz + vec3(cell) * vol.spacing.xyz;
}
