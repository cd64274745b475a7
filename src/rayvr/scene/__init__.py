"""Scenes: the CPU model, built-in scenes, glTF loading, the GPU scene and its BVH."""
from ..materials.material import AlphaMode, Material, MaterialTable, TextureRef
from .model import (DEFAULT_ENVIRONMENT, FEATURES, Camera, Environment, Instance, InstanceTable, Light, LightList,
                    LightType, Mesh, Scene, Texture)
from .gpu_scene import GpuScene


def load_scene(path) -> Scene:
    """Load a glTF 2.0 scene (.gltf or .glb) into a `Scene`; bad input raises SceneError."""
    import os

    from ..errors import SceneError
    from .gltf import load_gltf

    if not isinstance(path, (str, os.PathLike)):
        raise SceneError(f"load_scene: expected the path of a .gltf or .glb file, got {path!r}")
    return load_gltf(path)


__all__ = ["Scene", "Mesh", "Instance", "InstanceTable", "Light", "LightList", "LightType", "Camera", "Texture",
           "Environment", "DEFAULT_ENVIRONMENT", "Material", "MaterialTable", "AlphaMode", "TextureRef", "FEATURES",
           "GpuScene", "load_scene", "load_environment"]


def load_environment(spec, where: str = "environment", strength: float = 1.0) -> Environment:
    """An Environment from a colour ('1,1,1', 0.5, (r, g, b)) or an equirectangular image file."""
    from .environment import load_environment as load

    return load(spec, where, strength)
