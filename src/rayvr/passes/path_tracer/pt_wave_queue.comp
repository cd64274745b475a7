// PathTracer, wavefront form with PTW_COMPACT (pt_wave.glsl): after a shading dispatch filled queue
// ptq_out, its workgroup count for the dispatches over it (the trace kernel's and the next
// shading's), and queue ptq_in, which the shading read and the next one fills, emptied. With
// ptq_reset (a sample's start) both queues emptied.
#include "pt_pixel.glsl"
#include "pt_wave.glsl"

layout(local_size_x = 1) in;
uniform bool ptq_reset;

void main() {
    ptq_args[2] = uvec4(0u);   // the persistent trace kernel starts at the queue's first path
    if (ptq_reset) {
        ptq_args[0] = ptq_args[1] = uvec4(0u, 1u, 1u, 0u);
        return;
    }
    uint n = ptq_args[ptq_out].w;
    ptq_args[ptq_out] = uvec4((n + uint(PTW_GROUP_SIZE) - 1u) / uint(PTW_GROUP_SIZE), 1u, 1u, n);
    if (ptq_in < 2u) ptq_args[ptq_in] = uvec4(0u, 1u, 1u, 0u);
}
