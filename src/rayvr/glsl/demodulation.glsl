// Light without, and back with, the directional albedos of the surface it left (bsdf.glsl
// bsdf_albedo, seen from the view): what SVGF filters, and what the trace decision's fill carries
// from a traced pixel to another, so texture detail and the lobes' change with the view angle stay
// each pixel's own. Albedos count as at least DEMODULATION_EPS both ways, so a black lobe
// round-trips exactly. Needs views.glsl and gbuffer.glsl (GBUF_READER) first.
#pragma once
#include "path_vertex.glsl"

const float DEMODULATION_EPS = 1e-3;

// The directional albedos of the diffuse and specular lobes at G-buffer surface g seen from `view`.
void surface_albedos(GSurface g, uint view, out vec3 diffuse, out vec3 specular) {
    PathVertex s = path_vertex_at_gbuffer(g, view);
    bsdf_albedo(s.bsdf, s.n, s.v, diffuse, specular);
}

vec3 demodulate(vec3 light, vec3 albedo) { return max(light, vec3(0.0)) / max(albedo, vec3(DEMODULATION_EPS)); }

vec3 remodulate(vec3 illumination, vec3 albedo) { return illumination * max(albedo, vec3(DEMODULATION_EPS)); }
