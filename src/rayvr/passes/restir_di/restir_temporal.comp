// ReSTIR DI stage 2, temporal reuse (restir_temporal.glsl), after a candidates stage that traced
// visibility rays.
#include "restir_stage.glsl"
#include "restir_temporal.glsl"

layout(rgba32ui) readonly uniform uimage2DArray reservoirs_in;   // this frame's candidates
layout(rgba32ui) writeonly uniform uimage2DArray reservoirs_out;

void main() {
    ivec3 p;
    GSurface g;
    PathVertex s;
    ivec3 size = imageSize(reservoirs_out);
    if (!restir_pixel(size, p, g, s)) return;
    Reservoir c = reservoir_unpack(imageLoad(reservoirs_in, p));
    uint hints = restir_hints_at(p);
    float c_at_c = c.weight > 0.0 ? restir_target_of(s, restir_specular_traced(g), hints, reservoir_light_id(c)) : 0.0;
    imageStore(reservoirs_out, p, reservoir_pack(restir_temporal_reuse(p, size, g, s, hints, c, c_at_c)));
}
