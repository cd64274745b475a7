"""Every malformed graph gets a one-line GraphError that names the pass/pin and the fix."""
import re

import pytest

from rayvr.errors import GraphError, OptionError
from rayvr.rendergraph import Reflection, RenderGraph, RenderPass
from rayvr.rendergraph.render_pass import Choice


class Src(RenderPass):
    PROPERTIES = {"format": "rgba8", "scale": 1.0, "layers": 0}

    def reflect(self, cd):
        r = Reflection()
        out = r.add_output("out").format(self.format)
        if self.scale != 1.0:
            out.scaled(self.scale)
        if self.layers:
            out.views(self.layers)
        r.add_input("opt").optional()
        return r


class Sink(RenderPass):
    PROPERTIES = {"format": "", "size": [], "layers": 0}

    def reflect(self, cd):
        r = Reflection()
        inp = r.add_input("color")
        if self.format:
            inp.format(self.format)
        if self.size:
            inp.texture_size(*self.size)
        if self.layers:
            inp.views(self.layers)
        r.add_input("extra").optional()
        r.add_output("result").format("rgba8")
        return r


def chain(**sink_props):
    g = RenderGraph("G")
    g.add_pass(Src(), "A")
    g.add_pass(Sink(sink_props), "B")
    g.add_edge("A.out", "B.color")
    g.mark_output("B.result")
    return g


def error_of(fn) -> str:
    with pytest.raises(GraphError) as err:
        fn()
    msg = str(err.value)
    assert "\n" not in msg, msg
    return msg


def test_valid_chain_plans():
    plan = chain().plan(size=(8, 8), views=2)
    assert plan.order == ["A", "B"]


def test_empty_graph_and_no_outputs():
    assert "graph 'G' is empty: add passes with add_pass" in error_of(lambda: RenderGraph("G").plan())
    g = RenderGraph("G")
    g.add_pass(Src(), "A")
    assert "has no marked output: mark one with mark_output('Pass.pin')" in error_of(g.plan)


def test_cycle_names_the_passes():
    g = chain()
    g.add_pass(Src(), "C")
    g.add_edge("B.result", "C.opt")
    g.add_edge("C.out", "A.opt")
    msg = error_of(g.plan)
    assert re.search(r"has a cycle (A -> B -> C -> A|B -> C -> A -> B|C -> A -> B -> C): remove one", msg), msg


def test_unknown_pass_gets_did_you_mean():
    g = chain()
    msg = error_of(lambda: g.add_edge("Aa.out", "B.extra"))
    assert "has no pass 'Aa' (did you mean 'A'?)" in msg
    assert "has no pass 'Bx'" in error_of(lambda: g.mark_output("Bx.result"))
    assert "has no pass 'Q'" in error_of(lambda: g.remove_pass("Q"))


def test_unknown_pin_gets_did_you_mean_and_the_pin_list():
    g = chain()
    g.add_pass(Src(), "C")
    g.add_edge("C.outt", "B.extra")
    msg = error_of(g.plan)
    assert "edge 'C.outt' -> 'B.extra': pass 'C' (Src) has no output 'outt' (did you mean 'out'?); its outputs: out" in msg
    g = chain()
    g.add_pass(Src(), "C")
    g.add_edge("C.out", "B.colour")
    assert "pass 'B' (Sink) has no input 'colour' (did you mean 'color'?)" in error_of(g.plan)


def test_edge_from_an_input_pin():
    g = chain()
    g.add_pass(Src(), "C")
    g.add_edge("B.extra", "C.opt")
    assert "'B.extra' is an input pin, not an output; use one of B's outputs: result" in error_of(g.plan)


def test_required_input_unconnected():
    g = RenderGraph("G")
    g.add_pass(Src(), "A")
    g.add_pass(Sink(), "B")
    g.mark_output("B.result")
    msg = error_of(g.plan)
    assert "pass 'B' (Sink): required input 'color' is not connected; add_edge('<Pass>.<output>', 'B.color')" in msg


def test_two_sources_into_one_input():
    g = chain()
    g.add_pass(Src(), "C")
    g.add_edge("C.out", "B.color")
    assert ("input 'B.color' has two sources 'A.out' and 'C.out': remove one with "
            "remove_edge('C.out', 'B.color')") in error_of(g.plan)


def test_format_size_and_view_conflicts():
    msg = error_of(chain(format="rgba16f").plan)
    assert "edge 'A.out' -> 'B.color': format conflict, 'A.out' is rgba8 but 'B.color' needs rgba16f" in msg
    assert "insert a Blit" in msg
    msg = error_of(lambda: chain(size=[4, 4]).plan(size=(8, 8)))
    assert "size conflict, 'A.out' is 8x8 but 'B.color' needs 4x4; insert a Blit to rescale" in msg
    msg = error_of(lambda: chain(layers=1).plan(views=2))
    assert "view-count conflict, 'A.out' has 2 layers but 'B.color' needs 1" in msg


def test_output_marked_on_input_pin_or_unknown_pin():
    g = chain()
    g.mark_output("B.color")
    assert "mark_output('B.color'): 'B.color' is an input pin, not an output; use one of B's outputs: result" \
        in error_of(g.plan)
    g = chain()
    g.mark_output("B.reslt")
    assert "has no output 'reslt' (did you mean 'result'?)" in error_of(g.plan)
    assert "name the pin, e.g. 'B.dst'" in error_of(lambda: chain().mark_output("B"))


def test_editing_errors():
    g = chain()
    assert "already has a pass 'A'; choose another name" in error_of(lambda: g.add_pass(Src(), "A"))
    assert "must be a non-empty string without '.'" in error_of(lambda: g.add_pass(Src(), "x.y"))
    assert "connect a pin to a pin" in error_of(lambda: g.add_edge("A.out", "B"))
    assert "edge 'A.out' -> 'B.color' already exists" in error_of(lambda: g.add_edge("A.out", "B.color"))
    assert "a pass cannot feed itself" in error_of(lambda: g.add_edge("A.out", "A.opt"))
    assert "no edge 'A.out' -> 'B.extra'" in error_of(lambda: g.remove_edge("A.out", "B.extra"))
    assert "not a marked output" in error_of(lambda: g.unmark_output("A.out"))
    assert "is not a RenderPass" in error_of(lambda: g.add_pass(object(), "Z"))
    assert "write 'Pass.pin'" in error_of(lambda: g.add_edge("A..out", "B.extra"))
    with pytest.raises(OptionError, match=r"update_pass\('A'\): pass A: unknown property 'fromat' \(did you mean 'format'\?\)"):
        g.update_pass("A", {"fromat": "rgba16f"})


def test_remove_pass_drops_its_edges_and_outputs_and_update_pass_keeps_them():
    g = chain()
    g.add_pass(Src(), "C")
    g.add_edge("C.out", "B.extra")
    g.add_edge("C", "A")
    new = g.update_pass("C", {"format": "rgba16f"})
    assert g.get_pass("C") is new and new.name == "C" and new.format == "rgba16f"
    assert [(e.src, e.dst) for e in g.edges] == [("A.out", "B.color"), ("C.out", "B.extra"), ("C", "A")]
    assert g.plan().order == ["C", "A", "B"]
    g.remove_pass("C")
    assert [(e.src, e.dst) for e in g.edges] == [("A.out", "B.color")]
    g.remove_pass("B")
    assert g.outputs == [] and g.edges == []


def test_camel_case_aliases_are_the_same_methods():
    g = RenderGraph("G")
    g.addPass(Src(), "A")
    g.addPass(Sink(), "B")
    g.addEdge("A.out", "B.color")
    g.markOutput("B.result")
    assert g.getPass("A").name == "A"
    g.unmarkOutput("B.result")
    g.removeEdge("A.out", "B.color")
    assert g.outputs == [] and g.edges == []


class Picky(RenderPass):
    PROPERTIES = {"mode": "fast", "filter": "box", "kernel": "wide"}
    CHOICES = {"mode": {"fast": "fewer samples", "exact": ""}, "filter": ("box", "tent"),
               "kernel": {"narrow": Choice("3 taps", 7), "wide": Choice("", 2)}}

    def reflect(self, cd):
        return Reflection()


def test_a_property_with_choices_takes_only_them_and_the_error_lists_them():
    assert Picky(mode="exact", filter="tent").get_properties() == {"mode": "exact", "filter": "tent", "kernel": "wide"}
    with pytest.raises(OptionError) as err:
        Picky(mode="slow")
    assert str(err.value) == "pass Picky: property 'mode' is 'slow'; use 'fast' (fewer samples) or 'exact'"
    with pytest.raises(OptionError, match=r"^pass Picky: property 'filter' is 3; use 'box' or 'tent'$"):
        Picky(filter=3)
    p = Picky()
    with pytest.raises(OptionError):   # set_properties checks too, and leaves the old value
        p.set_properties({"filter": "gauss"})
    assert p.filter == "box"
    # a Choice carries the number the shaders see: the message shows its meaning, choice_define its number
    with pytest.raises(OptionError, match=r"^pass Picky: property 'kernel' is 'flat'; use 'narrow' \(3 taps\) or 'wide'$"):
        p.set_properties({"kernel": "flat"})
    assert p.choice_define("kernel") == 2
    p.set_properties({"kernel": "narrow"})
    assert p.choice_define("kernel") == 7


def test_a_number_property_refuses_nan_and_infinities_and_the_graph_stays_as_it_was():
    with pytest.raises(OptionError, match=r"^pass Src: property 'scale' must be a finite number, got nan$"):
        Src(scale=float("nan"))
    g = chain()
    for bad in (float("inf"), float("-inf"), float("nan")):
        with pytest.raises(OptionError, match=r"^update_pass\('A'\): pass A: property 'layers' must be a finite number"):
            g.update_pass("A", {"layers": bad})
    assert g.get_pass("A").layers == 0


def test_properties_that_are_not_a_dict_are_an_option_error_naming_the_pass():
    with pytest.raises(OptionError, match=r"^pass Src: properties must be a dict of name: value, got \[1\]$"):
        Src([1])
    with pytest.raises(OptionError, match=r"^update_pass\('A'\): pass A: properties must be a dict of name: value, got 'x'$"):
        chain().update_pass("A", "x")


def test_a_size_or_view_count_that_is_not_a_number_is_a_graph_error():
    assert "compile size 'abc' x 1 views: give size=(width, height)" in error_of(lambda: chain().plan(size="abc"))
    assert "compile size (8, 8) x 'two' views" in error_of(lambda: chain().plan(size=(8, 8), views="two"))


def test_every_counted_property_takes_whole_numbers_in_its_range_and_only_those():
    """RenderPass.WHOLE, one rule for every pass: a counted property's least value comes back as an
    int, and a fraction, a value below the least or above the most is refused with a
    message naming the pass, the property and the range."""
    import rayvr.passes  # noqa: F401  (registers the passes)
    from rayvr.rendergraph.registry import registered_passes

    counted = {name: cls for name, cls in registered_passes().items() if cls.WHOLE}
    assert {"RTShadows", "RTReflections", "SVGF", "ProbeGI", "PathTracer", "ReSTIRDI", "TraceDecision"} <= set(counted)
    for name, cls in counted.items():
        p = cls()
        for key, (least, most, _) in cls.WHOLE.items():
            assert key in cls.PROPERTIES, (name, key)
            p.set_properties({key: float(least)})
            assert type(p.get_properties()[key]) is int and p.get_properties()[key] == least
            bad = [least - 1, least + 0.5] + ([most + 1] if most is not None else [])
            for value in bad:
                with pytest.raises(OptionError, match=rf"pass {p.name}: property '{key}' must be an integer "
                                                      rf"(from {least} to {most}|>= {least})"):
                    p.set_properties({key: value})
