"""OpenGL context, capability probe, shader loading and GPU timing."""
from .context import (Capabilities, GpuContext, attach_context, create_context, get_context, probe,
                      set_context, use_context)
from .shaders import ShaderSource, compute_program, preprocess, raster_program
from .timer import GpuTimer

__all__ = ["Capabilities", "GpuContext", "attach_context", "create_context", "get_context", "probe", "set_context",
           "use_context", "ShaderSource", "compute_program", "preprocess", "raster_program", "GpuTimer"]
