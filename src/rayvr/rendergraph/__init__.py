"""Render graphs: passes, pins, compile (validate, prune, order, allocate), execute, save/load.

Names load on first use, so the pass registry (`registry.py`) imports without the compiler."""
from __future__ import annotations

import importlib

_LAZY = {
    # name: the submodule that defines it
    **dict.fromkeys(("FORMATS", "Format", "get_format"), "formats"),
    **dict.fromkeys(("CompileData", "Pin", "PinDirection", "PinKind", "Reflection", "RenderContext", "RenderData",
                     "RenderPass"), "render_pass"),
    "Edge": "graph_data",
    "GraphData": "graph_data",
    "RenderGraph": "graph",
    "CompiledGraph": "compiled",
    "Plan": "compiler",
    **dict.fromkeys(("PassStats", "Profile"), "profile"),
    **dict.fromkeys(("add_pass_source", "create_pass", "createPass", "get_pass_class", "register_pass",
                     "registered_passes"), "registry"),
    **dict.fromkeys(("CompileReport", "ResourceInfo"), "report"),
}

__all__ = list(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rayvr.rendergraph' has no attribute '{name}'")
