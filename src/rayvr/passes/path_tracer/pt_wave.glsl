// The wavefront path tracer's state (pt_wave_shade.comp, pt_wave_trace.comp): one path per
// invocation slot, its fields in structure-of-arrays order (field f of path i at f * pt_wave_paths + i,
// so a warp's loads of one field are contiguous), 16 bytes a field. The shade kernel runs
// everything but the rays (path.glsl's pt_vertex and the answers); the trace kernel only traces,
// so its registers are the traversal's alone: in the megakernel the BSDF's registers cost the
// traversal its occupancy (a probe of 64 more live values in the shading made it 2.35x slower).
#pragma once

layout(std430) buffer PtWave { uvec4 pt_wave[]; };
uniform uint pt_wave_paths;   // slots in all: the stride between fields

// The fields (PTW_RADIANCE, ...: rayvr/gpu/records.py PATH_WAVE_FIELDS): first those the shade
// kernel keeps for itself, then what the trace kernel reads and answers. A path's generator is
// kept as its one changing word (rng_word): the rest is the pixel's and the sample's.
#include "pt_wave_fields.glsl"

#define PTW_ALIVE 1u         // the path goes on
#define PTW_SCATTERED 2u     // rays.scattered: its BSDF ray is to be traced
#define PTW_DELTA 4u
#define PTW_TRANSMITTED 8u
#define PTW_ESCAPED 32u      // the camera ray escaped: PTW_EMITTED is the background
#define PTW_FOUND 1u
#define PTW_OCCLUDED 2u
#define PTW_SHADOW 4u        // a shadow ray was traced

uvec4 ptw_load(uint field, uint i) { return pt_wave[field * pt_wave_paths + i]; }
void ptw_store(uint field, uint i, uvec4 v) { pt_wave[field * pt_wave_paths + i] = v; }
vec4 ptw_loadf(uint field, uint i) { return uintBitsToFloat(ptw_load(field, i)); }
void ptw_storef(uint field, uint i, vec3 v, float w) { ptw_store(field, i, floatBitsToUint(vec4(v, w))); }
void ptw_storefu(uint field, uint i, vec3 v, uint w) { ptw_store(field, i, uvec4(floatBitsToUint(v), w)); }

// This invocation's slot in the state, the same in both kernels (their dispatches have one shape):
// the list index over a pixel list, else the workgroup's slots then the lane, so that a warp's
// slots are contiguous.
uint ptw_slot() {
#if PIXEL_LIST_INPUT
    return gl_GlobalInvocationID.x;
#else
    uvec3 n = gl_NumWorkGroups, w = gl_WorkGroupID;
    return ((w.z * n.y + w.y) * n.x + w.x) * uint(RAY_GROUP_SIZE)
           + gl_LocalInvocationIndex;
#endif
}

uniform ivec3 pt_wave_size;   // the output's width, height, views

// This invocation's pixel (false: none, past the image or the list).
bool ptw_pixel(out ivec3 p) {
#if PIXEL_LIST_INPUT
    uint i = gl_GlobalInvocationID.x;
    p = ivec3(0);
    if (i >= pixel_count) return false;
    p = pixel_list_unpack(pixel_items[i]);
    return true;
#else
    p = ray_group_pixel();
#if TRACE_DECISION   // a pixel the decision reconstructs has no path (its fill comes after)
    if (all(lessThan(p, pt_wave_size)) && decision_reconstructed(p)) return false;
#endif
    return all(lessThan(p, pt_wave_size));
#endif
}
