// The BSDF's lobes: one file each (after Falcor's lobes), chosen by sets of flags (after Mitsuba 3's
// BSDFFlags and BSDFContext). A lobe has an index (its sampling probability BsdfParams.lobe_p[i],
// its case in the dispatchers below), a bit 1 << index in the lobe sets that bsdf.glsl's functions
// take, and a file `bsdf_lobe_<name>.glsl` with its functions. Adding a lobe (sheen, clearcoat):
// its file, and here its index, its bit in the sets it belongs to, its include, its place in
// BSDF_EACH_LOBE and its cases.
//
// A lobe <x> provides what it has of (a missing case contributes nothing):
//   float bsdf_<x>_weight(b, nv, ab)      its sampling weight at n.v, before the lobes' normalisation
//   bool  bsdf_<x>_scatters(b)            whether it carries light (then it keeps a share of 2%)
//   bool  bsdf_<x>_sample(...)            a direction from u.xy (and u_split in [0,1)); false: none
//   void  bsdf_<x>_set_view(inout b)      what it caches at n.v
//   a lobe in BSDF_LOBES_GGX reflects through the GGX term the set shares (bsdf_eval_ggx):
//   void  bsdf_<x>_add_fresnel(b, vh, inout fresnel)           its Fresnel factor on that term
//   void  bsdf_<x>_add_reflection_share(b, p, v, l, inout s)  its probability p times the share of
//                                                             its samples that reflect towards l
//   the rest of its f |n.l|, and its probability p times the rest of its pdf, for l above or below:
//   vec3  bsdf_<x>_eval_above(b, n, v, l), bsdf_<x>_eval_below(b, n, v, l)
//   float bsdf_<x>_pdf_above(b, p, n, v, l), bsdf_<x>_pdf_below(b, p, n, v, l)
//   a smooth (delta) surface's mirror direction and straight or refracted one:
//   void  bsdf_<x>_add_delta_reflectance(b, nv, inout r), bsdf_<x>_add_mirror_share(b, p, nv, inout s)
//   vec3  bsdf_<x>_delta_transmittance(b, nv)
//   void  bsdf_<x>_add_albedo(b, inout albedo)   its directional albedo at n.v
#pragma once

const int BSDF_LOBE_SPECULAR = 0;   // GGX reflection of the dielectric's specular layer and the metal
const int BSDF_LOBE_DIFFUSE = 1;    // the dielectric's Lambert base
const int BSDF_LOBE_GLASS = 2;      // rough dielectric interface: reflection and transmission
const int BSDF_LOBE_COUNT = 3;
const int BSDF_LOBE_FALLBACK = BSDF_LOBE_SPECULAR;   // probability 1 when no lobe carries light
// A float per lobe, indexed by BSDF_LOBE_*: a vector of BSDF_LOBE_COUNT components (vec4 for a fourth
// lobe), not a float array, which the compiler may keep in local memory when it crosses functions
#define BsdfLobeFloats vec3

const uint BSDF_LOBES_ALL = (1u << BSDF_LOBE_COUNT) - 1u;
const uint BSDF_LOBES_DIFFUSE = 1u << BSDF_LOBE_DIFFUSE;
// all but the diffuse base: what a reflection pass traces (bsdf_sample_specular), the albedo's
// specular part
const uint BSDF_LOBES_SPECULAR = (1u << BSDF_LOBE_SPECULAR) | (1u << BSDF_LOBE_GLASS);
const uint BSDF_LOBES_GGX = (1u << BSDF_LOBE_SPECULAR) | (1u << BSDF_LOBE_GLASS);   // share the GGX reflection

bool bsdf_lobe_in(uint lobes, int lobe) { return (lobes & (1u << lobe)) != 0u; }

// STEP(lobe) for every lobe in index order: the composites are straight-line code over the lobes
// (a loop left rolled would keep the dispatch at run time and change how sums are rounded).
#define BSDF_EACH_LOBE(STEP) STEP(BSDF_LOBE_SPECULAR) STEP(BSDF_LOBE_DIFFUSE) STEP(BSDF_LOBE_GLASS)

#include "bsdf_terms.glsl"
#include "bsdf_lobe_specular.glsl"
#include "bsdf_lobe_diffuse.glsl"
#include "bsdf_lobe_glass.glsl"

// ---- the dispatchers: a case per lobe that has the function -----------------------------------
float bsdf_lobe_weight(int lobe, BsdfParams b, float nv, vec2 ab) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: return bsdf_specular_weight(b, nv, ab);
    case BSDF_LOBE_DIFFUSE: return bsdf_diffuse_weight(b, nv, ab);
    case BSDF_LOBE_GLASS: return bsdf_glass_weight(b, nv, ab);
    }
    return 0.0;
}

bool bsdf_lobe_scatters(int lobe, BsdfParams b) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: return bsdf_specular_scatters(b);
    case BSDF_LOBE_DIFFUSE: return bsdf_diffuse_scatters(b);
    case BSDF_LOBE_GLASS: return bsdf_glass_scatters(b);
    }
    return false;
}

// A direction of `lobe`; `delta` when it is a delta there (then l is exact), `transmitted` when l
// is below, `q` the probability of the branch it chose against (glass: F at the microfacet).
bool bsdf_lobe_sample(int lobe, BsdfParams b, vec3 n, vec3 v, vec2 u, float u_split, out vec3 l, out bool delta,
                      out bool transmitted, out float q) {
    delta = false;
    transmitted = false;
    q = 0.0;
    l = n;
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: return bsdf_specular_sample(b, n, v, u, l, delta);
    case BSDF_LOBE_DIFFUSE: return bsdf_diffuse_sample(n, u, l);
    case BSDF_LOBE_GLASS: return bsdf_glass_sample(b, n, v, u, u_split, l, delta, transmitted, q);
    }
    return false;
}

void bsdf_lobe_set_view(int lobe, inout BsdfParams b) {
    switch (lobe) {
    case BSDF_LOBE_GLASS: bsdf_glass_set_view(b); break;
    }
}

void bsdf_lobe_add_fresnel(int lobe, BsdfParams b, float vh, inout vec3 fresnel) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: bsdf_specular_add_fresnel(b, vh, fresnel); break;
    case BSDF_LOBE_GLASS: bsdf_glass_add_fresnel(b, vh, fresnel); break;
    }
}

void bsdf_lobe_add_reflection_share(int lobe, BsdfParams b, float p, vec3 v, vec3 l, inout float share) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: bsdf_specular_add_reflection_share(p, share); break;
    case BSDF_LOBE_GLASS: bsdf_glass_add_reflection_share(b, p, v, l, share); break;
    }
}

vec3 bsdf_lobe_eval_above(int lobe, BsdfParams b, vec3 n, vec3 v, vec3 l) {
    switch (lobe) {
    case BSDF_LOBE_DIFFUSE: return bsdf_diffuse_eval_above(b, n, v, l);
    }
    return vec3(0.0);
}

vec3 bsdf_lobe_eval_below(int lobe, BsdfParams b, vec3 n, vec3 v, vec3 l) {
    switch (lobe) {
    case BSDF_LOBE_GLASS: return bsdf_glass_eval_below(b, n, v, l);
    }
    return vec3(0.0);
}

float bsdf_lobe_pdf_above(int lobe, BsdfParams b, float p, vec3 n, vec3 v, vec3 l) {
    switch (lobe) {
    case BSDF_LOBE_DIFFUSE: return bsdf_diffuse_pdf_above(p, n, l);
    }
    return 0.0;
}

float bsdf_lobe_pdf_below(int lobe, BsdfParams b, float p, vec3 n, vec3 v, vec3 l) {
    switch (lobe) {
    case BSDF_LOBE_GLASS: return bsdf_glass_pdf_below(b, p, n, v, l);
    }
    return 0.0;
}

void bsdf_lobe_add_delta_reflectance(int lobe, BsdfParams b, float nv, inout vec3 r) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: bsdf_specular_add_delta_reflectance(b, nv, r); break;
    case BSDF_LOBE_GLASS: bsdf_glass_add_delta_reflectance(b, nv, r); break;
    }
}

void bsdf_lobe_add_mirror_share(int lobe, BsdfParams b, float p, float nv, inout float share) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: bsdf_specular_add_mirror_share(p, share); break;
    case BSDF_LOBE_GLASS: bsdf_glass_add_mirror_share(b, p, nv, share); break;
    }
}

vec3 bsdf_lobe_delta_transmittance(int lobe, BsdfParams b, float nv) {
    switch (lobe) {
    case BSDF_LOBE_GLASS: return bsdf_glass_delta_transmittance(b, nv);
    }
    return vec3(0.0);
}

void bsdf_lobe_add_albedo(int lobe, BsdfParams b, inout vec3 albedo) {
    switch (lobe) {
    case BSDF_LOBE_SPECULAR: bsdf_specular_add_albedo(b, albedo); break;
    case BSDF_LOBE_DIFFUSE: bsdf_diffuse_add_albedo(b, albedo); break;
    case BSDF_LOBE_GLASS: bsdf_glass_add_albedo(b, albedo); break;
    }
}
