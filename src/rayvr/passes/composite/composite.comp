// Hybrid composite: per pixel, the lighting its effect asked for. RASTER pixels keep the unshadowed
// direct light; SHADOWS and above take the ray-traced shadowed light; REFLECTIONS and above add
// the reflected radiance (already weighted by the specular BSDF); PATH_TRACED pixels take the
// path tracer's (accumulated) radiance when the graph has one.
#define GBUF_READER 1
#include "gbuffer.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

uniform sampler2DArray direct_tex;
#if HAS_SHADOWS
uniform sampler2DArray shadowed_tex;
#endif
#if HAS_REFLECTIONS
uniform sampler2DArray reflection_tex;
#endif
#if HAS_PATHS
uniform sampler2DArray path_tex;
#endif
layout(rgba16f) writeonly uniform image2DArray dst;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(dst)))) return;
    uint effect = gbuf_effect_at(p);
    vec3 c = texelFetch(direct_tex, p, 0).rgb;
    if (effect != GBUF_NO_GEOMETRY) {
#if HAS_SHADOWS
        if (effect >= EFFECT_SHADOWS) c = texelFetch(shadowed_tex, p, 0).rgb;
#endif
#if HAS_REFLECTIONS
        if (effect >= EFFECT_REFLECTIONS) c += texelFetch(reflection_tex, p, 0).rgb;
#endif
#if HAS_PATHS
        if (effect == EFFECT_PATH_TRACED) c = texelFetch(path_tex, p, 0).rgb;
#endif
    }
    imageStore(dst, p, vec4(to_half_range(c), 1.0));
}
