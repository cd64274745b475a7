"""RTShadows: ray-traced shadowed direct light for SHADOWS materials and above."""
from .rt_shadows import RTShadows

__all__ = ["RTShadows"]
