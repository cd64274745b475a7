// The wavefront path tracer's state (pt_wave_shade.comp, pt_wave_trace.comp): one path per
// invocation slot, its fields in structure-of-arrays order (field f of path i at f * pt_wave_paths + i,
// so a warp's loads of one field are contiguous), 16 bytes a field. The shade kernel runs
// everything but the rays (path.glsl's pt_vertex and the answers); the trace kernel only traces,
// so its registers are the traversal's alone: in the megakernel the BSDF's registers cost the
// traversal its occupancy (a probe of 64 more live values in the shading made it 2.35x slower).
#pragma once

layout(std430) buffer PtWave { uvec4 pt_wave[]; };
uniform uint pt_wave_paths;   // slots in all: the stride between fields

#define PTW_RADIANCE 0u   // path radiance, rays' pdf
#define PTW_BETA 1u       // path beta, rays' cone width
#define PTW_MEDIUM 2u     // path medium, rays' cone spread
#define PTW_NEE 3u        // rays' light sample contribution and shadow distance (< 0: none)
#define PTW_POS 4u        // rays' vertex (the camera's eye for a camera ray), flags
#define PTW_NG 5u         // rays' geometric normal, the path's BLEND seed
#define PTW_NEE_DIR 6u    // shadow ray direction, Rng state
#define PTW_DIR 7u        // BSDF ray direction, Rng group
#define PTW_EMITTED 8u    // what the first vertex emits towards the eye (or the background), Rng index
#define PTW_HIT 9u        // trace kernel: t, barycentrics, instance
#define PTW_ANSWER 10u    // trace kernel: primitive, PTW_FOUND | PTW_OCCLUDED, BLEND rays traced so far
#define PTW_FIRST_DIFFUSE 11u   // PT_LOBES: the split's fields
#define PTW_FIRST_TOTAL 12u
#define PTW_SHARE 13u
#define PTW_NEE_DIFFUSE 14u

#define PTW_ALIVE 1u         // the path goes on
#define PTW_SCATTERED 2u     // rays.scattered: its BSDF ray is to be traced
#define PTW_DELTA 4u
#define PTW_TRANSMITTED 8u
#define PTW_CAMERA 16u       // the BSDF ray slot holds the camera ray
#define PTW_ESCAPED 32u      // the camera ray escaped: PTW_EMITTED is the background
#define PTW_FOUND 1u
#define PTW_OCCLUDED 2u

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
    return all(lessThan(p, pt_wave_size));
#endif
}
