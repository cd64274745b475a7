"""PathTracer: unidirectional path tracing, from the camera or from the G-buffer."""
from .path_tracer import PathTracer

__all__ = ["PathTracer"]
