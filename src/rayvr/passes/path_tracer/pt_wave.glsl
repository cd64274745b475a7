// The wavefront path tracer's state (pt_wave_shade.comp, pt_wave_trace.comp): one path per
// invocation slot, its fields in structure-of-arrays order (field f of path i at f * pt_wave_paths + i,
// so a warp's loads of one field are contiguous), 16 bytes a field. The shade kernel runs
// everything but the rays (path.glsl's pt_vertex and the answers); the trace kernel only traces,
// so its registers are the traversal's alone: in the megakernel the BSDF's registers cost the
// traversal its occupancy (a probe of 64 more live values in the shading made it 2.35x slower).
//   PTW_COMPACT 1: after a sample's first shading dispatch (over the image or the list) the kernels
//   run over a queue of the paths still going (PtQueue, indirect dispatch): each shading appends
//   the paths it continues to the other queue, a path that ends adds its light to the outputs at
//   once, and pt_wave_queue.comp turns the count into the next dispatch's size.
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

#if PTW_COMPACT
// Two queues of path slots: per queue uvec4(workgroups, 1, 1, paths) (its indirect dispatch, 16 B
// each), uvec4(the persistent trace kernel's next path, 0, 0, 0), PTW_BINS x 3 counters of the
// direction sort (the paths per bin, each bin's first place, the places taken), then the slots of
// queue 0, then those of queue 1, pt_wave_paths each. With PTW_SORT a shading appends to queue 0
// each slot with its BSDF ray's octant in bits 29..31, and pt_wave_sort.comp places them in
// queue 1 by octant (a counting sort), so a warp's rays take their BVH children in one order.
#define PTW_BINS 8u
#define PTW_BIN_SHIFT 29
layout(std430) buffer PtQueue { uvec4 ptq_args[3]; uint ptq_bins[3u * PTW_BINS]; uint ptq_items[]; };
uniform uint ptq_in;           // the queue this dispatch runs over; 2: none (the image or the list)
uniform uint ptq_out;          // the queue a shading dispatch appends the paths it continues to
uniform uvec3 ptw_groups;      // the image-wide dispatch's workgroups (a slot's pixel)

// Queue path slot i (whose next BSDF ray runs along d) for the next stage.
void ptq_push(uint i, vec3 d) {
#if PTW_SORT
    uint bin = uint(d.x < 0.0) | (uint(d.y < 0.0) << 1) | (uint(d.z < 0.0) << 2);
    atomicAdd(ptq_bins[bin], 1u);
    i |= bin << PTW_BIN_SHIFT;
#endif
    ptq_items[ptq_out * pt_wave_paths + atomicAdd(ptq_args[ptq_out].w, 1u)] = i;
}
#endif

// The pixel of slot i (ptw_slot inverted).
ivec3 ptw_slot_pixel(uint i) {
#if PIXEL_LIST_INPUT
    return pixel_list_unpack(pixel_items[i]);
#elif PTW_COMPACT
    uint group = i / uint(RAY_GROUP_SIZE);
    uvec3 w = uvec3(group % ptw_groups.x, (group / ptw_groups.x) % ptw_groups.y, group / (ptw_groups.x * ptw_groups.y));
    return ray_group_pixel_of(w, i % uint(RAY_GROUP_SIZE));
#else
    return ivec3(0);
#endif
}

// This invocation's pixel (false: none, past the image or the list).
bool ptw_pixel(out ivec3 p) {
#if PIXEL_LIST_INPUT
    return pixel_list_item(p);
#else
    p = ray_group_pixel();
#if TRACE_DECISION   // a pixel the decision reconstructs has no path (its fill comes after)
    if (all(lessThan(p, pt_wave_size)) && decision_reconstructed(p)) return false;
#endif
    return all(lessThan(p, pt_wave_size));
#endif
}

// This invocation's path: its slot i and pixel p (false: none). From a queue (PTW_COMPACT, ptq_in
// < 2) the queue's j-th path, else the invocation's own slot.
bool ptw_path(out uint i, out ivec3 p) {
    i = 0u;
    p = ivec3(0);
#if PTW_COMPACT
    if (ptq_in < 2u) {
        uint j = gl_GlobalInvocationID.x;
        if (j >= ptq_args[ptq_in].w) return false;
        i = ptq_items[ptq_in * pt_wave_paths + j];
        p = ptw_slot_pixel(i);
        return true;
    }
#endif
    if (!ptw_pixel(p)) return false;
    i = ptw_slot();
    return true;
}
