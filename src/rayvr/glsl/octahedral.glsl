// Unit vectors as octahedral coordinates in [-1, 1]^2 (Cigolle et al. 2014, "A Survey of Efficient
// Representations for Independent Unit Vectors"), and packed in two snorm16 (about 1e-4 radians at
// worst): the probe atlases' tiles (probe_gi.glsl), SVGF's filter key and the deferred probe
// records (probe_records.glsl).
#pragma once

vec2 oct_sign(vec2 v) { return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

vec2 oct_encode(vec3 d) {
    vec2 p = d.xy / (abs(d.x) + abs(d.y) + abs(d.z) + 1e-20);
    return d.z >= 0.0 ? p : (1.0 - abs(p.yx)) * oct_sign(p);
}

vec3 oct_decode(vec2 e) {
    vec3 d = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (d.z < 0.0) d.xy = (1.0 - abs(d.yx)) * oct_sign(d.xy);
    return normalize(d);
}

uint oct_pack_snorm16(vec3 d) { return packSnorm2x16(oct_encode(d)); }
vec3 oct_unpack_snorm16(uint bits) { return oct_decode(unpackSnorm2x16(bits)); }
