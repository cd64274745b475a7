// RTReflections' second dispatch with probe GI: the probe lookups rt_reflections.comp (PROBE_RECORDS)
// recorded at each hit of each pixel's reflection path (glsl/probe_records.glsl), done here where
// no ray is traced, and added to the reflected radiance it stored. The same pixels as the first
// dispatch (the list, indirectly, or with PIXELS_2D the image in the same tiles).
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "pixel_list.glsl"
#include "probe_records.glsl"
#include "nonfinite.glsl"

#if PIXELS_2D
layout(local_size_x = RAY_GROUP_SIZE) in;
#else
layout(local_size_x = PIXEL_LIST_GROUP) in;
#endif
layout(rgba16f) uniform image2DArray dst;   // read, then written back with the probes' light
layout(rgba32ui) readonly uniform uimage2DArray probe_hits;
layout(rgba32ui) readonly uniform uimage2DArray probe_factors;

void main() {
    ivec3 p;
    if (!ray_pass_pixel(EFFECT_REFLECTIONS, imageSize(dst), p)) return;
    int views = imageSize(dst).z;
    vec3 gi = vec3(0.0);
    for (int bounce = 0; bounce < MAX_BOUNCES; ++bounce) {
        ivec3 q = ivec3(p.xy, probe_record_layer(p.z, bounce, views));
        gi += probe_record_radiance(probe_record_unpack(imageLoad(probe_hits, q), imageLoad(probe_factors, q)));
    }
    gi = nonfinite_scrub(gi);
    if (!any(notEqual(gi, vec3(0.0)))) return;   // nothing to add: the first dispatch's value stands
    vec4 c = imageLoad(dst, p);
    imageStore(dst, p, vec4(to_half_range(c.rgb + gi), c.a));
}
