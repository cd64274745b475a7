"""rayvr: hybrid raster/ray-traced rendering for VR headsets, composed as render graphs.

    import rayvr as rv
    scene = rv.scenes.cornell_box()
    g = rv.graphs.hybrid()
    with rv.Renderer(scene, g, sink=rv.xr.SimulatedHeadset(preset="index")) as r: ...

Submodules load on first use, so `import rayvr` stays cheap and never needs pyopenxr, a display
or the viewer extra (glfw, imgui-bundle).
"""
from __future__ import annotations

import importlib

from .errors import (ClusterError, GpuError, GraphError, OptionError, OutputError, RayvrError, SceneError, SceneWarning,
                     ShaderError, ViewerError, XrError)
from .materials.effect import Effect
from .rendergraph.registry import add_pass_source

__version__ = "0.1.0"

# rayvr's own passes register when a graph first names one it has not seen (a JSON graph, create_pass)
add_pass_source("rayvr.passes")

_LAZY = {
    # name: (module, attribute or None for the module itself)
    "gpu": ("rayvr.gpu", None),
    "rendergraph": ("rayvr.rendergraph", None),
    "passes": ("rayvr.passes", None),
    "scene": ("rayvr.scene", None),
    "scenes": ("rayvr.scene.builtin", None),
    "materials": ("rayvr.materials", None),
    "graphs": ("rayvr.graphs", None),
    "xr": ("rayvr.xr", None),
    "study": ("rayvr.study", None),
    "tune": ("rayvr.tune", None),
    "cluster": ("rayvr.cluster", None),   # Ray is imported only when a Cluster starts
    "RenderGraph": ("rayvr.rendergraph.graph", "RenderGraph"),
    "RenderPass": ("rayvr.rendergraph.render_pass", "RenderPass"),
    "Renderer": ("rayvr.renderer", "Renderer"),
    "load_scene": ("rayvr.scene", "load_scene"),
    "viewer": ("rayvr.viewer", None),
    "view": ("rayvr.viewer", "view"),   # imports glfw and imgui-bundle only when called
}

__all__ = ["Effect", "RayvrError", "ClusterError", "GpuError", "GraphError", "OptionError", "OutputError", "SceneError",
           "SceneWarning", "ShaderError", "ViewerError", "XrError", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        module, attr = _LAZY[name]
        mod = importlib.import_module(module)
        value = mod if attr is None else getattr(mod, attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rayvr' has no attribute '{name}'")
