"""Scenes: the CPU model, built-in scenes, glTF loading, the GPU scene and its BVH."""
from ..materials.material import AlphaMode, Material, MaterialTable, TextureRef
from .model import FEATURES, Camera, Instance, InstanceTable, Light, LightType, Mesh, Scene, Texture
from .gpu_scene import GpuScene


def load_scene(path) -> Scene:
    """Load a glTF 2.0 scene (.gltf or .glb) into a `Scene`; bad input raises SceneError."""
    from .gltf import load_gltf

    return load_gltf(path)


__all__ = ["Scene", "Mesh", "Instance", "InstanceTable", "Light", "LightType", "Camera", "Texture", "Material",
           "MaterialTable", "AlphaMode", "TextureRef", "FEATURES", "GpuScene", "load_scene"]
