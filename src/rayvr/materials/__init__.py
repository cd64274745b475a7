"""Materials: the glTF metallic-roughness model and per-material effect ids."""
from .effect import Effect
from .material import AlphaMode, Material, MaterialTable, TextureRef

__all__ = ["Effect", "AlphaMode", "Material", "MaterialTable", "TextureRef"]
