// The BSDF's lobes: one file each (after Falcor's lobes), chosen by sets of flags (after Mitsuba 3's
// BSDFFlags and BSDFContext). A lobe has an index (its sampling probability BsdfParams.lobe_p[i]),
// a bit 1 << index in the lobe sets that bsdf.glsl's functions take, and a file
// `bsdf_lobe_<name>.glsl` with its terms. bsdf.glsl's composites (set_view, the lobe
// probabilities, eval, pdf, the sampler, the albedos) call each lobe's terms by name, tested
// against the set's bits: written over a lobe table with a dispatcher per term they compiled
// 6-14% slower (docs/adding-a-lobe.md). Adding a lobe (sheen, clearcoat): its file, and here its
// index, its bit in the sets it belongs to and its include; in bsdf.glsl its call in each composite.
//
// A lobe <x> provides what it has of (bsdf.glsl's composites call the ones it has):
//   bool  bsdf_<x>_sample(...)            a direction from u.xy (and u_split in [0,1)); false: none
//   void  bsdf_<x>_set_view(inout b)      what it caches at n.v
//   a lobe in BSDF_LOBES_GGX reflects through the GGX term the set shares (bsdf_eval_ggx):
//   void  bsdf_<x>_add_fresnel(b, vh, inout fresnel)           its Fresnel factor on that term
//   the rest of its f |n.l|, for l above or below:
//   vec3  bsdf_<x>_eval_above(b, n, v, l), bsdf_<x>_eval_below(b, n, v, l)
//   a smooth (delta) surface's straight or refracted direction: vec3 bsdf_<x>_delta_transmittance(b, nv)
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

#include "bsdf_terms.glsl"
#include "bsdf_lobe_specular.glsl"
#include "bsdf_lobe_diffuse.glsl"
#include "bsdf_lobe_glass.glsl"
