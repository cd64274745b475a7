"""The compile stages one by one (rayvr.rendergraph.compiler: validate, reflect, prune, order,
resolve, alias) and the barriers the bind stage derives from the pins' access kinds."""
import pytest

import rayvr as rv
from rayvr.errors import GraphError
from rayvr.passes.basic import Blit, Clear
from rayvr.rendergraph import Reflection, RenderGraph, RenderPass
from rayvr.rendergraph import compiler as C
from rayvr.rendergraph.compiled import frame_barriers
from rayvr.rendergraph.render_pass import HOST_READ_BITS, Access, barrier_bits


class Writer(RenderPass):
    """Writes one output the way `how` says (image store, SSBO, framebuffer)."""

    PROPERTIES = {"how": "image", "kind": "texture"}

    def reflect(self, cd):
        r = Reflection()
        pin = r.add_output("dst").format("rgba16f")
        if self.kind == "buffer":
            pin.buffer(64)
        pin.accessed(self.how)
        return r


class Reader(RenderPass):
    """Reads `src` the way `how` says and writes an image."""

    PROPERTIES = {"how": "sampled", "kind": "texture"}

    def reflect(self, cd):
        r = Reflection()
        pin = r.add_input("src")
        if self.kind == "buffer":
            pin.buffer(64)
        pin.accessed(self.how)
        r.add_output("dst").format("rgba16f")
        return r


def two(writer, reader):
    g = RenderGraph("Two")
    g.add_pass(writer, "W")
    g.add_pass(reader, "R")
    g.add_edge("W.dst", "R.src")
    g.mark_output("R.dst")
    return g


def test_validate_finds_cycles_and_double_sources_and_orders_by_insertion():
    g = RenderGraph("G")
    for n in ("A", "B", "C"):
        g.add_pass(Blit(), n)
    g.add_edge("A.dst", "B.src")
    g.add_edge("B.dst", "C.src")
    g.mark_output("C.dst")
    topo = C.validate(g, (8, 8), 2)
    assert topo.order == ["A", "B", "C"] and topo.views == 2
    assert topo.into[("C", "src")].src == "B.dst"
    g.add_edge("C", "A")
    with pytest.raises(GraphError, match="cycle A -> B -> C -> A"):
        C.validate(g, (8, 8), 1)
    g.remove_edge("C", "A")
    g.add_edge("A.dst", "C.src")
    with pytest.raises(GraphError, match="input 'C.src' has two sources 'B.dst' and 'A.dst'"):
        C.validate(g, (8, 8), 1)


def test_reflect_propagates_formats_downstream_and_checks_pins():
    g = RenderGraph("G")
    g.add_pass(Clear(format="rgba8"), "A")
    g.add_pass(Blit(), "B")   # Blit's format follows its source when unset
    g.add_edge("A.dst", "B.src")
    g.mark_output("B.dst")
    refl = C.reflect(C.validate(g, (8, 4), 1))
    assert refl.compile_data["B"].input_formats == {"src": "rgba8"}
    assert refl.shapes[("B", "dst")] == ("rgba8", (8, 4), 1)
    g.mark_output("B.nope")
    with pytest.raises(GraphError, match="has no output 'nope'"):
        C.reflect(C.validate(g, (8, 4), 1))


class Skippable(Blit):
    PROPERTIES = {**Blit.PROPERTIES, "skip": ""}

    def skip_reason(self, cd):
        return self.skip or None


def test_prune_gives_each_dropped_pass_its_reason():
    g = RenderGraph("G")
    g.add_pass(Clear(), "A")
    g.add_pass(Skippable(skip="the scene has nothing for it"), "B")
    g.add_pass(Blit(), "C")
    g.add_pass(Clear(), "Orphan")
    g.add_edge("A.dst", "B.src")
    g.add_edge("B.dst", "C.src")
    g.mark_output("C.dst")
    g.mark_output("A.dst")
    topo = C.validate(g, (8, 8), 1)
    pruning = C.prune(topo, C.reflect(topo))
    assert pruning.pruned == {"B": "the scene has nothing for it",
                              "C": "required input 'src' comes from 'B', which was pruned "
                                   "(B: the scene has nothing for it)",
                              "Orphan": "feeds no marked output"}
    assert pruning.outputs == ["A.dst"] and "C.dst" in pruning.unavailable


def test_order_refuses_an_unconnected_required_input():
    g = RenderGraph("G")
    g.add_pass(Blit(), "B")
    g.mark_output("B.dst")
    topo = C.validate(g, (8, 8), 1)
    refl = C.reflect(topo)
    with pytest.raises(GraphError, match="required input 'src' is not connected"):
        C.order(topo, refl, C.prune(topo, refl))


def test_resolve_and_alias_share_slots_between_disjoint_lifetimes():
    g = RenderGraph("Chain")
    g.add_pass(Clear(format="rgba16f"), "P0")
    for i in range(1, 5):
        g.add_pass(Blit(format="rgba16f"), f"P{i}")
        g.add_edge(f"P{i - 1}.dst", f"P{i}.src")
    g.mark_output("P4.dst")
    topo = C.validate(g, (8, 8), 1)
    refl = C.reflect(topo)
    pruning = C.prune(topo, refl)
    kept = C.order(topo, refl, pruning)
    resources, bindings = C.resolve(topo, refl, pruning, kept)
    assert (resources["P1.dst"].first, resources["P1.dst"].last) == (1, 2)
    assert bindings["P2"] == {"src": "P1.dst", "dst": "P2.dst"}
    slots = C.alias(resources)
    # P0 and P2 (and P1 and P3) live apart and share; the marked P4.dst has a slot of its own
    assert resources["P0.dst"].slot == resources["P2.dst"].slot
    assert resources["P1.dst"].slot == resources["P3.dst"].slot
    assert len(slots) == 3 and slots[resources["P4.dst"].slot].resources == ["P4.dst"]


def test_plan_times_every_stage_and_the_report_names_them(gpu):
    cg = _blit_pair().compile(size=(8, 8), gpu=gpu)
    assert list(cg.report().stages) == list(C.STAGES)
    assert "compile stages: validate" in str(cg.report())


def _blit_pair():
    g = RenderGraph("Pair")
    g.add_pass(Clear(), "A")
    g.add_pass(Blit(), "B")
    g.add_edge("A.dst", "B.src")
    g.mark_output("B.dst")
    return g


@pytest.mark.parametrize("write,read,kind,bits", [
    ("image", "sampled", "texture", barrier_bits([Access.SAMPLED])),
    ("image", "image", "texture", barrier_bits([Access.IMAGE])),
    ("storage", "storage", "buffer", barrier_bits([Access.STORAGE])),
    ("storage", "indirect", "buffer", barrier_bits([Access.INDIRECT])),
    ("framebuffer", "sampled", "texture", 0),   # draws write coherently
])
def test_barrier_before_a_reader_matches_how_it_reads_what_was_written(write, read, kind, bits):
    g = two(Writer(how=write, kind=kind), Reader(how=read, kind=kind))
    before, final = frame_barriers(g.plan(size=(8, 8)))
    # a writer's SSBO stores wait for the previous frame's reads of the buffer (write after read);
    # for textures the end-of-frame barrier already carries the image bit
    war = barrier_bits([Access.STORAGE]) if write == "storage" else 0
    assert before == [war, bits]
    assert final == HOST_READ_BITS   # R.dst, image-stored, is read back or handed to a sink


def test_one_barrier_serves_every_later_reader_of_the_same_kind():
    g = RenderGraph("Fan")
    g.add_pass(Writer(), "W")
    g.add_pass(Reader(), "R1")
    g.add_pass(Reader(), "R2")
    g.add_edge("W.dst", "R1.src")
    g.add_edge("W.dst", "R2.src")
    g.mark_output("R1.dst")
    g.mark_output("R2.dst")
    before, _ = frame_barriers(g.plan(size=(8, 8)))
    assert before == [0, barrier_bits([Access.SAMPLED]), 0]


def test_hybrid_graph_barriers(gpu):
    """The hybrid graph with a raster G-buffer: no barrier after the draw, texture fetches before
    the composite (the ray passes image-stored its inputs), indirect arguments before the ray
    passes that dispatch from the compaction's lists, host-read bits at the end."""
    scene = rv.scenes.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.PATH_TRACED
    scene.materials["Floor"].effect = rv.Effect.REFLECTIONS
    plan = rv.graphs.hybrid(preset="raw", gbuffer="raster").plan(scene=scene, size=(8, 8), views=2, caps=gpu.caps)
    before, final = dict(zip(plan.order, frame_barriers(plan)[0])), frame_barriers(plan)[1]
    assert before["GBuffer"] == 0 and before["Direct"] == 0
    assert before["Shadows"] & barrier_bits([Access.INDIRECT]) == barrier_bits([Access.INDIRECT])
    assert before["Composite"] & barrier_bits([Access.SAMPLED])
    assert final == HOST_READ_BITS
