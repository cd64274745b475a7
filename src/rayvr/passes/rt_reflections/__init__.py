"""RTReflections: ray-traced mirror and glossy reflections for REFLECTIONS materials and above."""
from .rt_reflections import RTReflections

__all__ = ["RTReflections"]
