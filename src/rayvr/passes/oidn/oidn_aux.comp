// OIDNDenoise's auxiliary images from the G-buffer, every view in one dispatch: the first hit's
// albedo (the BSDF's diffuse + specular directional albedo, at most 1) and shading normal; zero
// where nothing was drawn. With `copy_color` it also copies `color` to `dst` (the pass disabled).
#define GBUF_READER 1
#include "views.glsl"
#include "gbuffer.glsl"
#include "path_vertex.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(rgba32f) writeonly uniform image2DArray aux_albedo;
layout(rgba32f) writeonly uniform image2DArray aux_normal;
uniform sampler2DArray color;
layout(rgba32f) writeonly uniform image2DArray dst;
uniform bool copy_color;

void main() {
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, imageSize(aux_albedo)))) return;
    if (copy_color) imageStore(dst, p, texelFetch(color, p, 0));
    vec3 albedo = vec3(0.0), n = vec3(0.0);
    if (gbuf_effect_at(p) != GBUF_NO_GEOMETRY) {
        GSurface g = gbuf_load(p);
        PathVertex s = path_vertex_at_gbuffer(g, uint(p.z));
        vec3 diffuse, specular;
        bsdf_albedo(s.bsdf, s.n, s.v, diffuse, specular);
        albedo = clamp(diffuse + specular, 0.0, 1.0);
        n = g.n;
    }
    imageStore(aux_albedo, p, vec4(albedo, 1.0));
    imageStore(aux_normal, p, vec4(n, 0.0));
}
