"""Render graphs: passes, pins, compile (validate, prune, order, allocate), execute, save/load."""
from .formats import FORMATS, Format, get_format
from .render_pass import (CompileData, Pin, PinDirection, PinKind, Reflection, RenderContext,
                          RenderData, RenderPass)

__all__ = ["FORMATS", "Format", "get_format", "CompileData", "Pin", "PinDirection", "PinKind",
           "Reflection", "RenderContext", "RenderData", "RenderPass"]
