// PathTracer, wavefront form with PTW_COMPACT (pt_wave.glsl): after a shading dispatch filled queue
// ptq_out, its workgroup count for the dispatches over it (the trace kernel's and the next
// shading's), and queue ptq_in, which the shading read and the next one fills, emptied. With
// PTW_SORT the shading filled queue 0 and pt_wave_sort.comp moves it to queue 1 next: both get
// the count, and each direction bin its first place in queue 1. With ptq_reset (a sample's
// start) both queues emptied.
#include "pt_pixel.glsl"
#include "pt_wave.glsl"

layout(local_size_x = 1) in;
uniform bool ptq_reset;

void main() {
    ptq_args[2] = uvec4(0u);   // the persistent trace kernel starts at the queue's first path
    if (ptq_reset) {
        ptq_args[0] = ptq_args[1] = uvec4(0u, 1u, 1u, 0u);
        for (uint b = 0u; b < 3u * PTW_BINS; ++b) ptq_bins[b] = 0u;
        return;
    }
    uint n = ptq_args[ptq_out].w;
    ptq_args[ptq_out] = uvec4((n + uint(PTW_GROUP_SIZE) - 1u) / uint(PTW_GROUP_SIZE), 1u, 1u, n);
#if PTW_SORT
    ptq_args[1] = ptq_args[0];
    uint first = 0u;
    for (uint b = 0u; b < PTW_BINS; ++b) {
        ptq_bins[PTW_BINS + b] = first;
        first += ptq_bins[b];
        ptq_bins[b] = 0u;
        ptq_bins[2u * PTW_BINS + b] = 0u;
    }
#else
    if (ptq_in < 2u) ptq_args[ptq_in] = uvec4(0u, 1u, 1u, 0u);
#endif
}
