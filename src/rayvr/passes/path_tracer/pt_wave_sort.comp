// PathTracer, wavefront form with PTW_SORT (pt_wave.glsl): the counting sort's scatter. Each path of
// queue 0 (slot | octant << PTW_BIN_SHIFT, as the shading queued it) goes to its octant's next place
// in queue 1, from the bin's first place pt_wave_queue.comp found; queue 0 is emptied for the next
// shading (its dispatch arguments were read when this dispatch began).
#include "pt_pixel.glsl"
#include "pt_wave.glsl"

#if PIXEL_LIST_INPUT
layout(local_size_x = PIXEL_LIST_GROUP) in;
#else
layout(local_size_x = RAY_GROUP_SIZE) in;
#endif

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j == 0u) ptq_args[0] = uvec4(0u, 1u, 1u, 0u);
    if (j >= ptq_args[1].w) return;
    uint item = ptq_items[j];
    uint bin = item >> PTW_BIN_SHIFT;
    uint place = ptq_bins[PTW_BINS + bin] + atomicAdd(ptq_bins[2u * PTW_BINS + bin], 1u);
    ptq_items[pt_wave_paths + place] = item & ((1u << PTW_BIN_SHIFT) - 1u);
}
