"""tools/pt_variants.py's variants are property sets ({pass: {property: value}}) applied to a graph:
a property a variant sets reaches the define its pass compiles with, an unknown property or a bad
value is refused with the pass's message, and every variant the tool lists fits the ready-made
graphs (the knobs it sets are real properties, with today's values as their defaults)."""
import importlib.util
from pathlib import Path

import pytest

import rayvr as rv
from rayvr.errors import OptionError
from rayvr.scene import builtin

TOOL = Path(__file__).resolve().parents[1] / "tools" / "pt_variants.py"


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location("pt_variants", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def graphs():
    return [rv.graphs.hybrid(preset="raw", gi="probes"), rv.graphs.hybrid(preset="raw"), rv.graphs.path_traced()]


def test_every_variant_applies_to_the_ready_made_graphs(tool):
    for name, props in tool.VARIANTS.items():
        applied = set()
        for g in graphs():
            applied |= tool.apply_variant(g, props)
            for pass_name, values in props.items():
                if pass_name in g.passes:
                    got = g.get_pass(pass_name).get_properties()
                    assert {k: got[k] for k in values} == values, (name, pass_name)
        assert applied == set(props) - {tool.SCENE}, f"variant {name}: no graph has {set(props) - applied}"
        scene = builtin.cornell_box()
        tool.apply_scene(scene, props)
        for key, value in props.get(tool.SCENE, {}).items():
            assert getattr(scene, key) == value


def test_defaults_are_the_shapes_the_passes_had():
    g = rv.graphs.hybrid(preset="raw", gi="probes")
    assert g.get_pass("GBuffer").get_properties()["tile"] == [4, 8]
    assert g.get_pass("GBuffer").get_properties()["view_group"] == 2
    assert {k: g.get_pass("Shadows").get_properties()[k] for k in ("dispatch_mode", "tile", "view_group")} == \
        {"dispatch_mode": "auto", "tile": [8, 4], "view_group": 16}
    assert {k: g.get_pass("Reflections").get_properties()[k] for k in ("tile", "view_group", "defer_probes")} == \
        {"tile": [8, 4], "view_group": 4, "defer_probes": True}
    composite = g.get_pass("Composite").get_properties()
    assert (composite["probe_tile"], composite["probe_view_group"]) == ([8, 4], 4)


def test_a_variant_changes_the_defines_its_passes_compile_with(gpu, tool):
    scene = builtin.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    scene.materials["Floor"].effect = rv.Effect.REFLECTIONS
    defines = {}
    for name in ("base", "sh_vg4", "reflections_list"):
        g = rv.graphs.hybrid(preset="raw")
        assert tool.apply_variant(g, tool.VARIANTS[name]) == set(tool.VARIANTS[name])
        compiled = g.compile(scene=scene, size=(16, 16), views=8, gpu=gpu, gpu_scene=rv.scene.GpuScene(gpu, scene))
        try:
            defines[name] = {p: dict(compiled.passes[p].defines()) for p in ("Shadows", "Reflections")}
        finally:
            compiled.release()
    base = defines["base"]
    assert base["Shadows"]["RAY_GROUP_Z"] == 8   # 16 asked, 8 views in the frame
    assert defines["sh_vg4"]["Shadows"]["RAY_GROUP_Z"] == 4
    assert defines["sh_vg4"]["Reflections"] == base["Reflections"]
    assert base["Reflections"]["PIXELS_2D"] == 1 and "PIXEL_LIST_INPUT" not in base["Reflections"]
    assert defines["reflections_list"]["Reflections"]["PIXELS_2D"] == 0
    assert defines["reflections_list"]["Reflections"]["PIXEL_LIST_INPUT"] == 1


def test_unknown_properties_and_bad_values_are_refused(tool):
    g = rv.graphs.hybrid(preset="raw")
    with pytest.raises(OptionError, match=r"unknown property 'view_groups' \(did you mean 'view_group'\?\)"):
        tool.apply_variant(g, {"Shadows": {"view_groups": 4}})
    with pytest.raises(OptionError, match=r"Shadows.*'tile' must be \[x, y\]"):
        tool.apply_variant(g, {"Shadows": {"tile": [8]}})
    with pytest.raises(OptionError, match=r"'view_group' must be an integer >= 1"):
        tool.apply_variant(g, {"GBuffer": {"view_group": 0}})
    with pytest.raises(OptionError, match=r"'dispatch_mode' is 'tiles'"):
        tool.apply_variant(g, {"Reflections": {"dispatch_mode": "tiles"}})
    assert g.get_pass("Shadows").get_properties()["view_group"] == 16   # nothing half-applied


def test_shape_properties_round_trip_the_json_form():
    g = rv.graphs.hybrid(preset="raw", gi="probes")
    g.update_pass("GBuffer", {"tile": (8, 8), "view_group": 4.0})   # a tuple, a whole float (the viewer's)
    assert g.get_pass("GBuffer").get_properties()["tile"] == [8, 8]
    back = rv.RenderGraph.from_dict(g.to_dict())
    for name, p in g.passes.items():
        assert back.get_pass(name).get_properties() == p.get_properties()


def test_runs_name_a_variant_or_a_tree(tool, tmp_path):
    _, root, props = tool.resolve_run("sh_vg4", {}, tool.VARIANTS)
    assert root == tool.ROOT and props == {"Shadows": {"view_group": 4}}
    (tmp_path / "src" / "rayvr").mkdir(parents=True)
    label, root, props = tool.resolve_run("old:base", {"old": str(tmp_path)}, tool.VARIANTS)
    assert label == "old:base"
    assert root == tmp_path.resolve() and props == {}
    with pytest.raises(SystemExit, match="unknown variant 'sh_vg3'"):
        tool.resolve_run("sh_vg3", {}, tool.VARIANTS)
    with pytest.raises(SystemExit, match="has no src/rayvr"):
        tool.resolve_run("nowhere:base", {"nowhere": str(tmp_path / "x")}, tool.VARIANTS)
