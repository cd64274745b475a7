"""Compile: pruning with reasons, order, lifetime aliasing on real GL objects, no per-frame
allocation, profile and report."""
import moderngl
import numpy as np
import pytest

from rayvr.errors import GraphError
from rayvr.passes.basic import Blit, Clear
from rayvr.rendergraph import Reflection, RenderGraph, RenderPass
from rayvr.rendergraph.profile import RollingTimes


class Maybe(RenderPass):
    """Clear-like pass the scene may not need (skip_reason), with an optional input."""

    PROPERTIES = {"skip": "", "value": 128 / 255, "ignore_src": ""}   # no .5 tie in unorm8

    def reflect(self, cd):
        r = Reflection()
        src = r.add_input("src").optional()
        if self.ignore_src:
            src.unused(self.ignore_src)
        r.add_output("dst").format("rgba8")
        return r

    def skip_reason(self, cd):
        return self.skip or None

    def compile(self, ctx, cd):
        self._clear = Clear(color=[self.value] * 4, format="rgba8")
        self._clear.compile(ctx, cd)
        self.saw_input = None

    def execute(self, ctx, data):
        self.saw_input = "src" in data
        self._clear.execute(ctx, data)


class History(RenderPass):
    def reflect(self, cd):
        r = Reflection()
        r.add_input("src")
        r.add_internal("prev").format("rgba16f")
        r.add_output("dst").format("rgba16f")
        return r


def chain(n, fmt="rgba16f"):
    g = RenderGraph("Chain")
    g.add_pass(Clear(color=[0.25, 0.5, 0.75, 1.0], format=fmt), "P0")
    for i in range(1, n):
        g.add_pass(Blit(format=fmt, filter="nearest"), f"P{i}")
        g.add_edge(f"P{i - 1}.dst", f"P{i}.src")
    g.mark_output(f"P{n - 1}.dst")
    return g


def test_chain_aliases_to_at_most_30_percent_and_shares_gl_objects(gpu):
    cg = chain(10).compile(size=(16, 8), views=2, gpu=gpu)
    rep = cg.report()
    assert rep.unaliased_bytes == 10 * 16 * 8 * 2 * 8
    assert rep.total_bytes <= 0.30 * rep.unaliased_bytes
    assert rep.bytes_saved == rep.unaliased_bytes - rep.total_bytes
    r = cg.resources
    assert r["P0.dst"] is r["P2.dst"] and r["P1.dst"] is r["P3.dst"]
    assert r["P0.dst"] is not r["P1.dst"]
    assert all(r["P9.dst"] is not r[f"P{i}.dst"] for i in range(9))   # marked outputs never alias
    assert len({id(o) for o in r.values()}) == 3
    info = {x.name: x for x in rep.resources}
    assert "P2.dst" in info["P0.dst"].aliased_with and info["P9.dst"].aliased_with == []
    cg.execute(cg.make_context())
    out = cg.read_output("P9.dst")
    assert (out == np.array([0.25, 0.5, 0.75, 1.0], np.float16)).all()   # aliasing kept values right


def test_different_formats_and_internal_pins_do_not_alias(gpu):
    g = RenderGraph("Mixed")
    g.add_pass(Clear(format="rgba8"), "A")
    g.add_pass(Blit(format="rgba16f"), "B")
    g.add_pass(Blit(format="rgba8"), "C")
    g.add_pass(History(), "H")
    g.add_edge("A.dst", "B.src")
    g.add_edge("B.dst", "C.src")
    g.add_edge("C.dst", "H.src")
    g.mark_output("H.dst")
    plan = g.plan(size=(4, 4))
    slots = {name: r.slot for name, r in plan.resources.items()}
    assert slots["A.dst"] != slots["B.dst"]             # formats differ
    assert slots["A.dst"] == slots["C.dst"]             # same format, [0,1] and [2,3] disjoint
    assert len({slots["H.prev"], slots["A.dst"], slots["B.dst"], slots["H.dst"]}) == 4
    assert plan.resources["H.prev"].internal


def test_a_source_read_only_by_unused_inputs_is_pruned_and_not_allocated(gpu):
    g = RenderGraph("Unused")
    g.add_pass(Clear(format="rgba16f"), "Lists")         # read by nobody who needs it
    g.add_pass(Clear(format="rgba16f"), "Shared")        # read by a used and an unused input
    g.add_pass(Maybe({"ignore_src": "runs over the whole image"}), "Ignores")
    g.add_pass(Maybe({"ignore_src": "not this time"}), "AlsoIgnores")
    g.add_pass(Blit(), "Reads")
    g.add_edge("Lists.dst", "Ignores.src")
    g.add_edge("Shared.dst", "AlsoIgnores.src")
    g.add_edge("Shared.dst", "Reads.src")
    for out in ("Ignores.dst", "AlsoIgnores.dst", "Reads.dst"):
        g.mark_output(out)
    cg = g.compile(size=(4, 4), views=1, gpu=gpu)
    assert cg.report().pruned == {"Lists": "feeds only inputs their passes leave unused: Ignores.src "
                                           "(runs over the whole image)"}
    assert "Lists.dst" not in cg.plan.resources
    assert cg.plan.bindings["AlsoIgnores"]["src"] is None and cg.plan.bindings["Reads"]["src"] == "Shared.dst"
    cg.execute(cg.make_context())
    assert g.get_pass("Ignores").saw_input is False


def test_prune_unused_skipped_and_chains_with_reasons(gpu):
    g = RenderGraph("Prune")
    g.add_pass(Clear(format="rgba8"), "Base")
    g.add_pass(Maybe({"skip": "no material uses REFLECTIONS"}), "Refl")
    g.add_pass(Blit(), "NeedsRefl")          # required input from a skipped pass
    g.add_pass(Maybe(), "UsesReflOptionally")
    g.add_pass(Clear(), "FeedsOnlyPruned")
    g.add_pass(Clear(), "Dangling")
    g.add_pass(Blit(), "Final")
    g.add_edge("FeedsOnlyPruned", "Refl")
    g.add_edge("Refl.dst", "NeedsRefl.src")
    g.add_edge("Refl.dst", "UsesReflOptionally.src")
    g.add_edge("Base.dst", "Final.src")
    g.add_edge("UsesReflOptionally", "Final")
    g.mark_output("Final.dst")
    g.mark_output("NeedsRefl.dst")
    g.mark_output("UsesReflOptionally.dst")
    cg = g.compile(size=(4, 4), views=1, gpu=gpu)
    assert cg.order == ["Base", "UsesReflOptionally", "Final"]
    p = cg.report().pruned
    assert p["Refl"] == "no material uses REFLECTIONS"
    assert p["NeedsRefl"] == ("required input 'src' comes from 'Refl', which was pruned "
                              "(Refl: no material uses REFLECTIONS)")
    assert p["Dangling"] == "feeds no marked output"
    assert p["FeedsOnlyPruned"] == "feeds only pruned passes (Refl)"
    cg.execute(cg.make_context())
    assert g.get_pass("UsesReflOptionally").saw_input is False
    assert cg.plan.compile_data["UsesReflOptionally"].input_formats == {}
    assert (cg.read_output("UsesReflOptionally.dst") == 128).all()
    with pytest.raises(GraphError, match=r"output 'NeedsRefl.dst' is not produced: required input 'src'"):
        cg.get_output("NeedsRefl.dst")
    with pytest.raises(GraphError, match=r"'Base.dst' is not a marked output of graph 'Prune'.*; mark it with mark_output\('Base.dst'\)"):
        cg.get_output("Base.dst")
    assert "NeedsRefl.dst not produced" in str(cg.report())


def test_order_is_topological_and_stable_by_insertion():
    g = RenderGraph("O")
    for name in ["D", "C", "B", "A"]:
        g.add_pass(Maybe(), name)
    g.add_edge("A", "D")
    g.add_edge("B.dst", "C.src")
    for name in ["D", "C"]:
        g.mark_output(f"{name}.dst")
    order = g.plan().order
    assert order.index("A") < order.index("D") and order.index("B") < order.index("C")
    assert order == ["B", "C", "A", "D"]   # earliest-inserted ready pass first: D waits for A


def test_second_execute_allocates_nothing(gpu, monkeypatch):
    cg = chain(4).compile(size=(8, 8), views=2, gpu=gpu)
    ctx = cg.make_context()
    cg.execute(ctx)
    calls = []
    for method in ["texture", "texture_array", "buffer", "compute_shader", "program", "sampler",
                   "query", "framebuffer", "renderbuffer", "vertex_array", "simple_vertex_array"]:
        original = getattr(moderngl.Context, method)

        def counting(self, *a, _name=method, _orig=original, **k):
            calls.append(_name)
            return _orig(self, *a, **k)

        monkeypatch.setattr(moderngl.Context, method, counting)
    for _ in range(3):
        cg.execute(ctx)
    assert calls == []
    chain(2).compile(size=(8, 8), gpu=gpu)     # the counter does see allocation
    assert "texture_array" in calls


def test_profile_rolling_stats_and_method(gpu):
    cg = chain(3).compile(size=(8, 8), views=1, gpu=gpu)
    ctx = cg.make_context()
    for _ in range(4):
        cg.execute(ctx)
    prof = cg.profile()
    assert prof.method == ("timer-query" if gpu.caps.timer_queries else "finish+wall")
    assert list(prof.passes) == ["P0", "P1", "P2"]
    for s in prof.passes.values():
        assert s.min_ms <= s.mean_ms <= s.max_ms and s.min_ms <= s.p95_ms <= s.max_ms
        assert s.samples == (4 if not gpu.caps.timer_queries else s.samples)
    assert prof.frames == 4 and "P1" in str(prof) and prof.method in str(prof)
    cg.set_profiling(False)
    cg.execute(ctx)
    assert cg.profile().method == "off"
    rt = RollingTimes(3)
    for v in [10, 1, 2, 3]:
        rt.add(v)
    s = rt.stats()
    assert (s.samples, s.mean_ms, s.min_ms, s.max_ms, s.last_ms) == (3, 2.0, 1.0, 3.0, 3.0)


def test_report_text_fields_left_out_and_extra(gpu):
    class Defines(Maybe):
        def defines(self):
            return {"USE_THING": 1}

    g = chain(3)
    g.add_pass(Defines(), "D")
    g.add_pass(Clear(), "Unused")
    g.add_edge("P2.dst", "D.src")
    g.mark_output("D.dst")

    class SceneReport:
        def __str__(self):
            return "scene: 3 meshes"

    cg = g.compile(size=(8, 8), views=2, gpu=gpu, extra_report=[SceneReport()])
    rep = cg.report()
    assert rep is cg.report()
    rep.left_out.append("no transmission: code and buffers left out")
    cg.add_report("bvh: 12 nodes")
    cg.add_report({"scene": "box", "left_out": {"SCENE_HAS_TEXTURES": "texture array"}})
    text = str(rep)
    for piece in ["render graph 'Chain': 8x8 x 2 view(s)", "order: P0 -> P1 -> P2 -> D", "Unused: feeds no marked output",
                  "D: USE_THING=1", "no transmission: code and buffers left out", "scene: 3 meshes",
                  "bvh: 12 nodes", "saved", "scene: box\nleft_out:\n  SCENE_HAS_TEXTURES: texture array"]:
        assert piece in text, piece
    assert rep.defines["D"] == {"USE_THING": 1}
    d = rep.as_dict()
    assert d["order"] == ["P0", "P1", "P2", "D"] and d["bytes_saved"] == rep.bytes_saved


def test_recompile_is_cheap_and_independent(gpu):
    g = chain(3)
    a = g.compile(size=(8, 8), gpu=gpu)
    g.update_pass("P0", {"color": [1, 0, 0, 1]})
    b = g.compile(size=(8, 8), gpu=gpu)
    a.execute(a.make_context())
    b.execute(b.make_context())
    assert (a.read_output("P2.dst")[..., 0] == np.float16(0.25)).all()
    assert (b.read_output("P2.dst")[..., 0] == 1).all()
    a.release()


def test_timer_query_path_reads_results_two_frames_late(gpu):
    import dataclasses
    import types

    # llvmpipe's queries return placeholders, but the code path is the one GPUs take.
    fake = types.SimpleNamespace(gl=gpu.gl, caps=dataclasses.replace(gpu.caps, timer_queries=True))
    cg = chain(3).compile(size=(8, 8), gpu=fake)
    ctx = cg.make_context()
    for _ in range(5):
        cg.execute(ctx)
    prof = cg.profile()
    assert prof.method == "timer-query"
    assert [s.samples for s in prof.passes.values()] == [3, 3, 3]


def test_each_timer_query_result_is_counted_once_around_profile_calls():
    import types

    from rayvr.gpu import GpuTimer

    frame = [0]

    class Query:   # elapsed = the number of the frame that began it, in ms
        def __init__(self):
            self.mglo = types.SimpleNamespace(begin=self.begin, end=lambda: None)

        def begin(self):
            self.frame = frame[0]

        @property
        def elapsed(self):
            return self.frame * 1e6

    timer = GpuTimer(types.SimpleNamespace(query=lambda time: Query()), True)
    seen = []

    def run_frames(n):
        for _ in range(n):
            timer.begin()
            timer.end()
            if (ms := timer.take()) is not None:
                seen.append(ms)
            frame[0] += 1

    run_frames(1)
    assert seen == [] and timer.resolve() == 0.0   # profile() waits only while a pass has no sample
    seen.append(timer.take())
    assert timer.take() is None
    run_frames(10)                                  # frame N's result arrives when frame N+2 begins
    assert seen == [float(n) for n in range(9)]     # frames 9 and 10 still in flight


def test_last_frame_ms_sums_the_latest_pass_times(gpu):
    from rayvr.passes.basic import Clear

    g = RenderGraph("Last")
    g.add_pass(Clear(format="rgba8"), "A")
    g.add_pass(Clear(format="rgba8"), "B")
    g.mark_output("A.dst")
    g.mark_output("B.dst")
    cg = g.compile(size=(4, 4), gpu=gpu)
    assert cg.last_frame_ms() == 0.0          # nothing timed yet
    cg.execute(cg.make_context())
    cg.execute(cg.make_context())
    prof = cg.profile()
    assert cg.last_frame_ms() == pytest.approx(sum(s.last_ms for s in prof.passes.values()))
