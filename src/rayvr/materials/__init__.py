"""Materials: the glTF metallic-roughness model and per-material effect ids."""
from .effect import Effect

__all__ = ["Effect"]
