"""DirectLighting: emission and unshadowed direct light for every G-buffer pixel."""
from .direct_lighting import DirectLighting

__all__ = ["DirectLighting"]
