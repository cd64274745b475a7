"""`RenderGraph`: the graph's data (`graph_data.GraphData`) with the verbs that read it: plan and
compile (`compiler.py`, `compiled.py`), save and load (`serialize.py`), draw (`picture.py`).

Editing is cheap and checks only names; `compile()` reflects the passes and validates pins,
formats, sizes and cycles. Falcor's camelCase names are aliases, so Falcor scripts port:
`addPass`, `addEdge`, `markOutput`, `removePass`, `updatePass`, ...
"""
from __future__ import annotations

from pathlib import Path

from ..gpu import get_context
from . import picture, serialize
from .compiled import CompiledGraph
from .compiler import plan_graph
from .graph_data import GraphData


class RenderGraph(GraphData):
    """A named graph of render passes. See docs/CONTRACTS.md and docs/adding-a-pass.md for the pass API."""

    # -- compile ---------------------------------------------------------------------------
    def plan(self, scene=None, size=(64, 64), views: int = 1, caps=None):
        """Validate, prune, order and plan resources without touching the GPU (a `compiler.Plan`)."""
        return plan_graph(self, scene=scene, size=size, views=views, caps=caps)

    def compile(self, scene=None, size=(64, 64), views: int = 1, gpu=None, gpu_scene=None,
                extra_report=(), profiling: bool = True) -> CompiledGraph:
        """Validate, prune, order, allocate (with lifetime aliasing) and compile the kept passes.

        `scene` is the CPU scene passes reflect on; `gpu_scene` the GpuScene they compile against;
        `extra_report` entries (e.g. `GpuScene.report()`) are appended to the compile report.
        """
        gpu = gpu or get_context()
        plan = self.plan(scene=scene, size=size, views=views, caps=gpu.caps)
        return CompiledGraph(self, plan, gpu, gpu_scene=gpu_scene, extra_report=extra_report,
                             profiling=profiling)

    # -- save / load / picture ----------------------------------------------------------------
    def save(self, path) -> Path:
        """Write a Falcor-style Python script (.py) or a JSON file (.json), chosen by suffix."""
        return serialize.save_graph(self, path)

    @classmethod
    def load(cls, path) -> RenderGraph:
        """Load a .py script (executes it: scripts are code) or a .json file (no code runs)."""
        return serialize.load_graph(path, cls)

    def to_dict(self) -> dict:
        """The JSON form `save(".json")` writes."""
        return serialize.graph_to_dict(self)

    @classmethod
    def from_dict(cls, data: dict, where: str = "graph") -> RenderGraph:
        """A graph from `to_dict()` data; errors name `where` and the field."""
        return serialize.graph_from_dict(data, cls, where)

    def to_script(self) -> str:
        """The Falcor-style Python script `save(".py")` writes."""
        return serialize.graph_to_script(self)

    def to_dot(self) -> str:
        """The graph as Graphviz DOT text."""
        return picture.graph_to_dot(self)

    def save_picture(self, path) -> Path:
        """Draw the graph as PNG/SVG/PDF (graphviz `dot` when on PATH, else matplotlib)."""
        return picture.save_picture(self, path)
