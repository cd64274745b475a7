"""Binding points of the frame-wide resources, injected into every shader as `#define`s so Python
and GLSL agree: SSBO 0 the views, 1-15 the GPU scene, two texture units for the scene's textures and environment.

A pass's own textures, images and buffers get their units and points from the program's
reflection by name (`rayvr.gpu.program_resources`), never from numbers in its code: they are
allocated around these (SSBOs from FIRST_PASS_SSBO, samplers skipping the scene's unit).
The BVH builders (`rayvr.scene.bvh_gpu`), which are not passes, use RAYVR_PASS_SSBO_0 + k.
"""

BINDINGS = {
    "RAYVR_VIEWS_SSBO": 0,
    "RAYVR_ENVIRONMENT_SSBO": 1,
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
    # 11: free (was a per-mesh table; InstanceData carries its BLAS root and first triangle)
    "RAYVR_TRIANGLE_MATERIAL_SSBO": 12,
    "RAYVR_TANGENT_SSBO": 13,
    "RAYVR_BSDF_TABLE_SSBO": 14,
    "RAYVR_LIGHT_TABLE_SSBO": 15,
    # a pass's own buffers start here
    "RAYVR_PASS_SSBO_0": 16,
    "RAYVR_PASS_SSBO_1": 17,
    "RAYVR_PASS_SSBO_2": 18,
    "RAYVR_PASS_SSBO_3": 19,
    "RAYVR_PASS_SSBO_4": 20,
    # atomic counter buffer binding (its own namespace): the running pass's non-finite counter
    "RAYVR_NONFINITE_COUNTER": 0,
    # image unit of the rays-per-view counters (rendergraph.ray_counters), the last of the 8 units
    # GL guarantees: a program that declares them binds its own images from 0 below it
    "RAYVR_RAY_COUNTER_IMAGE": 7,
    "RAYVR_SCENE_TEXTURE_UNIT": 8,
    "RAYVR_ENVIRONMENT_TEXTURE_UNIT": 9,
    "RAYVR_MAX_VIEWS": 64,
}

FIRST_PASS_SSBO = BINDINGS["RAYVR_PASS_SSBO_0"]
SCENE_TEXTURE_UNITS = (BINDINGS["RAYVR_SCENE_TEXTURE_UNIT"], BINDINGS["RAYVR_ENVIRONMENT_TEXTURE_UNIT"])

# GLSL storage blocks and samplers bound frame-wide (views, GpuScene.bind()), by name: a pass's
# program resources leave them at their fixed points.
SHARED_BLOCKS = {
    "ViewsBlock": "RAYVR_VIEWS_SSBO",
    "SceneVertices": "RAYVR_VERTEX_SSBO",
    "SceneIndices": "RAYVR_INDEX_SSBO",
    "RqBlasNodes": "RAYVR_BLAS_NODE_SSBO",
    "RqTlasNodes": "RAYVR_TLAS_NODE_SSBO",
    "SceneInstances": "RAYVR_INSTANCE_SSBO",
    "SceneMaterials": "RAYVR_MATERIAL_SSBO",
    "PunctualLights": "RAYVR_PUNCTUAL_LIGHT_SSBO",
    "EmissiveTriangles": "RAYVR_EMISSIVE_TRIANGLE_SSBO",
    "RqTriangles": "RAYVR_TRIANGLE_SSBO",
    "SceneTriangleMaterials": "RAYVR_TRIANGLE_MATERIAL_SSBO",
    "SceneTangents": "RAYVR_TANGENT_SSBO",
    "BsdfTables": "RAYVR_BSDF_TABLE_SSBO",
    "LightTable": "RAYVR_LIGHT_TABLE_SSBO",
    "EnvironmentData": "RAYVR_ENVIRONMENT_SSBO",
}
SHARED_IMAGES = {"rayvr_ray_counts": "RAYVR_RAY_COUNTER_IMAGE"}
SHARED_SAMPLERS = {"scene_textures": "RAYVR_SCENE_TEXTURE_UNIT", "scene_environment": "RAYVR_ENVIRONMENT_TEXTURE_UNIT"}
