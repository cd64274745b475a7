"""Binding points shared by every shader, injected as `#define`s so Python and GLSL agree.

0-1: frame-wide (views); 2-15: the GPU scene; 16+: a pass's own buffers.
Sampler units: 0-7 a pass's own textures, 8-15 the scene's textures.
"""

BINDINGS = {
    "RAYVR_VIEWS_SSBO": 0,
    # scene (rayvr.scene.GpuScene)
    "RAYVR_VERTEX_SSBO": 2,
    "RAYVR_INDEX_SSBO": 3,
    "RAYVR_BLAS_NODE_SSBO": 4,
    "RAYVR_TLAS_NODE_SSBO": 5,
    "RAYVR_INSTANCE_SSBO": 6,
    "RAYVR_MATERIAL_SSBO": 7,
    "RAYVR_PUNCTUAL_LIGHT_SSBO": 8,
    "RAYVR_EMISSIVE_TRIANGLE_SSBO": 9,
    "RAYVR_TRIANGLE_SSBO": 10,
    "RAYVR_MESH_SSBO": 11,
    "RAYVR_TRIANGLE_MATERIAL_SSBO": 12,
    "RAYVR_TANGENT_SSBO": 13,
    # a pass's own buffers start here
    "RAYVR_PASS_SSBO_0": 16,
    "RAYVR_PASS_SSBO_1": 17,
    "RAYVR_PASS_SSBO_2": 18,
    "RAYVR_PASS_SSBO_3": 19,
    "RAYVR_PASS_SSBO_4": 20,
    "RAYVR_SCENE_TEXTURE_UNIT": 8,
    "RAYVR_MAX_VIEWS": 64,
}
