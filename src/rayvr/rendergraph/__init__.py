"""Render graphs: passes, pins, compile (validate, prune, order, allocate), execute, save/load."""
from .formats import FORMATS, Format, get_format
from .render_pass import (CompileData, Pin, PinDirection, PinKind, Reflection, RenderContext,
                          RenderData, RenderPass)
from .graph import Edge, RenderGraph
from .compiled import CompiledGraph
from .compiler import Plan
from .profile import PassStats, Profile
from .registry import create_pass, createPass, get_pass_class, register_pass, registered_passes
from .report import CompileReport, ResourceInfo

__all__ = ["FORMATS", "Format", "get_format", "CompileData", "Pin", "PinDirection", "PinKind",
           "Reflection", "RenderContext", "RenderData", "RenderPass", "Edge", "RenderGraph",
           "CompiledGraph", "Plan", "PassStats", "Profile", "create_pass", "createPass", "get_pass_class", "register_pass",
           "registered_passes", "CompileReport", "ResourceInfo"]
