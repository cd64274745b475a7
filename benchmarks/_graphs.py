"""Graphs the benchmarks share."""
from __future__ import annotations

from rayvr.passes.basic import Blit, Clear
from rayvr.rendergraph import Reflection, RenderGraph, RenderPass


def linear_chain(passes: int, fmt: str = "rgba16f", name: str = "Chain") -> RenderGraph:
    """Clear -> Blit -> ... -> Blit (`passes` in all), every output the same size and format;
    only the last output is marked."""
    g = RenderGraph(name)
    g.add_pass(Clear(color=[0.25, 0.5, 0.75, 1.0], format=fmt), "P0")
    for i in range(1, passes):
        g.add_pass(Blit(format=fmt, filter="nearest"), f"P{i}")
        g.add_edge(f"P{i - 1}.dst", f"P{i}.src")
    g.mark_output(f"P{passes - 1}.dst")
    return g


class NullPass(RenderPass):
    """Declares one output like a real pass but does no GPU work: times the graph machinery."""

    def reflect(self, cd):
        r = Reflection()
        r.add_input("src").optional()
        r.add_output("dst").format("rgba8")
        return r


def null_chain(passes: int) -> RenderGraph:
    g = RenderGraph("NullChain")
    for i in range(passes):
        g.add_pass(NullPass(), f"N{i}")
        if i:
            g.add_edge(f"N{i - 1}.dst", f"N{i}.src")
    g.mark_output(f"N{passes - 1}.dst")
    return g
