"""A render graph as data: passes by instance name, data and ordering edges, marked outputs.

`GraphData` holds and edits them; editing is cheap and checks only names. What reads a graph
sits on top of it and knows it by these fields alone: the compiler (`compiler.py`), the
exporter and importer (`serialize.py`), the picture (`picture.py`), and `RenderGraph`
(`graph.py`), which is this data with those verbs. Falcor's camelCase names are aliases, so
Falcor scripts port: `addPass`, `addEdge`, `markOutput`, `removePass`, `updatePass`, ...
"""
from __future__ import annotations

import dataclasses

from ..errors import GraphError, OptionError, did_you_mean
from .registry import create_pass
from .render_pass import RenderPass


@dataclasses.dataclass(frozen=True)
class Edge:
    """'A.out' -> 'B.in' (data) or 'A' -> 'B' (ordering only: pins are None)."""

    src_pass: str
    src_pin: str | None
    dst_pass: str
    dst_pin: str | None

    @property
    def is_data(self) -> bool:
        return self.src_pin is not None

    @property
    def src(self) -> str:
        return self.src_pass if self.src_pin is None else f"{self.src_pass}.{self.src_pin}"

    @property
    def dst(self) -> str:
        return self.dst_pass if self.dst_pin is None else f"{self.dst_pass}.{self.dst_pin}"

    def __str__(self) -> str:
        return f"'{self.src}' -> '{self.dst}'"


def split_pin(ref: str, what: str = "pin") -> tuple[str, str | None]:
    """'Pass.pin' -> ('Pass', 'pin'); 'Pass' -> ('Pass', None)."""
    if not isinstance(ref, str) or not ref or ref.count(".") > 1 or ref.startswith(".") or ref.endswith("."):
        raise GraphError(f"{what} {ref!r}: write 'Pass.pin' for a pin or 'Pass' for a pass")
    name, _, pin = ref.partition(".")
    return name, (pin or None)


class GraphData:
    """A named graph of render passes, as data: what the compiler and the exporter read."""

    def __init__(self, name: str = "RenderGraph"):
        if not str(name).isidentifier():
            raise GraphError(f"graph name {name!r} must be an identifier (letters, digits, '_'), "
                             f"as it names the script's render_graph_<name>() function")
        self.name = str(name)
        self._passes: dict[str, RenderPass] = {}
        self._edges: list[Edge] = []
        self._outputs: list[str] = []

    # -- passes ----------------------------------------------------------------------------
    def add_pass(self, render_pass: RenderPass, name: str) -> RenderPass:
        """Add `render_pass` under instance `name` (sets `render_pass.name`); returns the pass."""
        if not isinstance(render_pass, RenderPass):
            raise GraphError(f"add_pass({name!r}): {render_pass!r} is not a RenderPass; "
                             f"pass an instance such as rv.passes.Blit()")
        if not isinstance(name, str) or not name or "." in name:
            raise GraphError(f"add_pass: pass name {name!r} must be a non-empty string without '.'")
        if name in self._passes:
            raise GraphError(f"add_pass: graph '{self.name}' already has a pass '{name}'; "
                             f"choose another name or remove_pass('{name}') first")
        render_pass.name = name
        self._passes[name] = render_pass
        return render_pass

    def create_pass(self, name: str, type_name: str, props: dict | None = None) -> RenderPass:
        """Add a new pass of registered class `type_name` under `name` (Falcor 7's create_pass)."""
        return self.add_pass(create_pass(type_name, props), name)

    def remove_pass(self, name: str) -> None:
        """Remove a pass with its edges and marked outputs."""
        self._require_pass(name, "remove_pass")
        del self._passes[name]
        self._edges = [e for e in self._edges if name not in (e.src_pass, e.dst_pass)]
        self._outputs = [o for o in self._outputs if split_pin(o)[0] != name]

    def update_pass(self, name: str, props: dict) -> RenderPass:
        """Replace pass `name` by a new instance of its class with `props` over its current
        properties; edges and marked outputs stay. Returns the new pass."""
        old = self._require_pass(name, "update_pass")
        new = type(old)(old.get_properties())
        new.name = name   # before the new values, so that their errors name this pass
        try:
            new.set_properties(props or {})
        except OptionError as exc:
            raise OptionError(f"update_pass('{name}'): {exc}") from exc
        self._passes[name] = new
        return new

    def get_pass(self, name: str) -> RenderPass:
        """The pass called `name`; GraphError with a did-you-mean when there is none."""
        return self._require_pass(name, "get_pass")

    @property
    def passes(self) -> dict[str, RenderPass]:
        """Passes by instance name, in insertion order (a copy)."""
        return dict(self._passes)

    # -- edges -----------------------------------------------------------------------------
    def add_edge(self, src: str, dst: str) -> Edge:
        """'A.out' -> 'B.in' connects data; 'A' -> 'B' only orders A before B."""
        sp, spin = split_pin(src, "add_edge source")
        dp, dpin = split_pin(dst, "add_edge destination")
        if (spin is None) != (dpin is None):
            raise GraphError(f"add_edge('{src}', '{dst}'): connect a pin to a pin ('A.out', 'B.in') "
                             f"or a pass to a pass ('A', 'B') for ordering only")
        self._require_pass(sp, f"add_edge('{src}', '{dst}')")
        self._require_pass(dp, f"add_edge('{src}', '{dst}')")
        if sp == dp:
            raise GraphError(f"add_edge('{src}', '{dst}'): a pass cannot feed itself; "
                             f"keep history in an internal pin instead")
        edge = Edge(sp, spin, dp, dpin)
        if edge in self._edges:
            raise GraphError(f"add_edge: edge {edge} already exists")
        self._edges.append(edge)
        return edge

    def remove_edge(self, src: str, dst: str) -> None:
        """Remove the edge `src` -> `dst`, spelled as it was added."""
        edge = Edge(*split_pin(src, "remove_edge source"), *split_pin(dst, "remove_edge destination"))
        if edge not in self._edges:
            known = [f"{e.src} -> {e.dst}" for e in self._edges]
            raise GraphError(f"remove_edge: no edge {edge} in graph '{self.name}'"
                             f"{did_you_mean(f'{edge.src} -> {edge.dst}', known)}")
        self._edges.remove(edge)

    @property
    def edges(self) -> list[Edge]:
        """Edges in the order they were added (a copy)."""
        return list(self._edges)

    # -- outputs ---------------------------------------------------------------------------
    def mark_output(self, ref: str) -> None:
        """Mark 'Pass.pin' as a graph output: it is kept, never aliased, readable after execute."""
        name, pin = split_pin(ref, "mark_output")
        if pin is None:
            raise GraphError(f"mark_output({ref!r}): name the pin, e.g. '{name}.dst'")
        self._require_pass(name, f"mark_output({ref!r})")
        if ref not in self._outputs:
            self._outputs.append(ref)

    def unmark_output(self, ref: str) -> None:
        """Stop marking 'Pass.pin' as a graph output."""
        if ref not in self._outputs:
            raise GraphError(f"unmark_output({ref!r}): not a marked output{did_you_mean(ref, self._outputs)}; "
                             f"marked: {', '.join(self._outputs) or '(none)'}")
        self._outputs.remove(ref)

    @property
    def outputs(self) -> list[str]:
        """Marked outputs as 'Pass.pin', in marking order (a copy)."""
        return list(self._outputs)

    # -- helpers ---------------------------------------------------------------------------
    def _require_pass(self, name: str, where: str) -> RenderPass:
        try:
            return self._passes[name]
        except KeyError:
            raise GraphError(f"{where}: graph '{self.name}' has no pass '{name}'"
                             f"{did_you_mean(str(name), self._passes)}; passes: "
                             f"{', '.join(self._passes) or '(none)'}") from None

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.name!r}, passes={list(self._passes)}, "
                f"edges={[f'{e.src}->{e.dst}' for e in self._edges]}, outputs={self._outputs})")

    # Falcor spellings
    addPass, removePass, updatePass, getPass = add_pass, remove_pass, update_pass, get_pass
    createPass = create_pass
    addEdge, removeEdge, markOutput, unmarkOutput = add_edge, remove_edge, mark_output, unmark_output
