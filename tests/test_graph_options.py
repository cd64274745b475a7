"""The ready-made graphs' options, declared once (rayvr.graph_options, rayvr.graphs.BUILDERS): the
command line's choices and help, the viewer's graph names, the error study's rows and the tuner's
option sets all follow the table, so a new denoiser is one entry. No GPU."""
import sys

import pytest

import rayvr as rv
from rayvr.cli.main import build_parser
from rayvr.errors import OptionError
from rayvr.graph_options import DENOISE, DIRECT, GI, NONE, OPTIONS, Choice, realtime_option_sets
from rayvr.graphs import BUILDERS, COMMAND_LINE_GRAPHS


@pytest.fixture
def extra_denoiser():
    """A denoiser added to the table as a new one would be: one Choice."""
    before = DENOISE.choices
    object.__setattr__(DENOISE, "choices", (*before, Choice("fake", "a test's denoiser, real time")))
    yield "fake"
    object.__setattr__(DENOISE, "choices", before)


def render_options() -> dict:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return {a.dest: a for a in sub.choices["render"]._actions}


def test_the_command_line_reads_the_table():
    options = render_options()
    assert options["graph"].choices == COMMAND_LINE_GRAPHS == ("hybrid", "path_traced")
    assert options["denoise"].choices == DENOISE.cli_choices == (NONE, "svgf", "oidn")
    assert options["gi"].choices == GI.cli_choices == (NONE, "probes")
    assert options["direct"].choices == DIRECT.cli_choices == (NONE, "restir")
    assert options["denoise"].help == ("none; svgf (SVGF + TAA over the frames, real time); oidn (Intel Open Image "
                                       "Denoise on the last frame, offline: needs rayvr[oidn]); default the preset's "
                                       "for hybrid, none for path_traced")
    assert options["preset"].choices == ("clean", "raw") and options["preset"].default == "clean"
    assert options["graph"].help == ("hybrid (per-material effects; default) or path_traced (every pixel, "
                                     "accumulated: reference renders)")


def test_a_new_denoiser_is_one_entry(extra_denoiser):
    from rayvr.study.configs import available_denoisers, path_traced_graph

    assert extra_denoiser in render_options()["denoise"].choices
    assert rv.graphs.denoiser(extra_denoiser) == extra_denoiser
    installed = ["svgf", "oidn"] if DENOISE["oidn"].available() else ["svgf"]   # oidn: the rayvr[oidn] extra
    assert available_denoisers() == [*installed, extra_denoiser] == available_denoisers(path_traced_graph)
    assert {"denoise": extra_denoiser} in realtime_option_sets()
    names = [c.name for c in rv.tune.standard_configs(rv.scenes.cornell_box(), spp=(1,))]
    assert "PATH_TRACED 1 spp + FAKE" in names and "all SHADOWS + FAKE" in names
    with pytest.raises(OptionError, match=r"denoise='x': use None \('none'\), 'svgf', 'oidn' or 'fake'"):
        rv.graphs.hybrid(preset="raw", denoise="x")


def test_the_tuner_tries_the_real_time_values_and_the_study_those_installed(monkeypatch):
    from rayvr.study.configs import available_denoisers, available_gi, hybrid_graph
    from rayvr.tune.tuner import OPTION_SETS, TUNED_OPTIONS, option_sets_for

    base = [{}, {"gi": "probes"}, {"denoise": "svgf"}, {"gi": "probes", "denoise": "svgf"}]
    sets = base + [{**s, "direct": "restir"} for s in base]
    assert realtime_option_sets() == list(OPTION_SETS) == sets
    assert [list(s) for s in OPTION_SETS] == [list(s) for s in sets]   # the keys in the same order too
    assert TUNED_OPTIONS == ("gi", "denoise", "direct") == tuple(o.name for o in OPTIONS)
    assert option_sets_for(hybrid_graph, {}) == sets
    assert not DENOISE["oidn"].realtime and DENOISE.is_realtime(None) and not DENOISE.is_realtime("oidn")
    assert available_gi() == ["probes"]
    monkeypatch.setitem(sys.modules, "pyoidn", None)   # the oidn extra missing
    assert not DENOISE["oidn"].available() and available_denoisers() == ["svgf"]
    with pytest.raises(OptionError, match=r"^--denoise oidn needs Intel Open Image Denoise"):
        DENOISE["oidn"].require("--denoise oidn")


def test_builders_by_name_for_the_viewer_and_the_study():
    from rayvr.study.configs import GRAPHS, accepts, hybrid_taa_graph
    from rayvr.viewer.app import resolve_graph

    assert list(BUILDERS) == list(GRAPHS) == ["hybrid", "hybrid_taa", "path_traced"]
    assert [o.name for o in BUILDERS["path_traced"].options] == ["denoise", "reuse", "foveation"]
    assert BUILDERS["hybrid"].takes("gi") and not BUILDERS["path_traced"].takes("gi")
    assert accepts(hybrid_taa_graph, "gi") and accepts(hybrid_taa_graph, "denoise")   # through hybrid's keywords
    assert resolve_graph("path_traced").name == "PathTraced" and resolve_graph(None).name == "Hybrid"
    with pytest.raises(OptionError, match=r"--graph nope: use hybrid or path_traced, or a saved graph"):
        resolve_graph("nope")


def test_the_viewer_rebuilds_a_graph_opened_by_name_with_an_option(gpu):
    pytest.importorskip("imgui_bundle", reason="the viewer extra is not installed: pip install 'rayvr[viewer]'")
    from rayvr.viewer.app import Viewer
    from rayvr.viewer.offscreen import OffscreenSurface

    scene = rv.scenes.cornell_box()
    with Viewer(scene, "hybrid", views=1, size=(16, 16), surface=OffscreenSurface((32, 32), gpu)) as v:
        v.step()   # the clean preset
        assert v.graph_builder == "hybrid" and {"SVGF", "Probes"} <= set(v.renderer.graph.passes)
        from rayvr.viewer.panels import graph as graph_section   # its options' combos draw

        v.ui.frame(v.surface.window_size, v.surface.framebuffer_size, 0.1, lambda: graph_section.draw(v, v.panels.state))
        v.set_graph_option("denoise", NONE)
        v.set_graph_option("gi", NONE)
        v.step()
        assert v.graph_options == {"denoise": None, "gi": None}
        assert not {"SVGF", "Probes"} & set(v.renderer.graph.passes) and v.renderer.graph is v.graph
        v.set_graph_option("denoise", "svgf")
        v.step()
        assert v.graph_options == {"denoise": "svgf", "gi": None} and "SVGF" in v.renderer.graph.passes
        with pytest.raises(OptionError, match=r"graph option taa: hybrid takes gi, denoise, direct"):
            v.set_graph_option("taa", True)
    given = rv.graphs.path_traced()
    with Viewer(scene, given, views=1, size=(16, 16), surface=OffscreenSurface((32, 32), gpu)) as v:
        assert v.graph_builder is None
        with pytest.raises(OptionError, match=r"was given or loaded"):
            v.set_graph_option("denoise", "svgf")
        assert v.graph is given


def test_the_hybrid_presets_clean_by_default_raw_one_flag_away():
    from rayvr.graph_options import PRESETS

    clean, raw = rv.graphs.hybrid(), rv.graphs.hybrid(preset="raw")
    assert {"Probes", "SVGF", "TAA"} <= set(clean.passes) and clean.outputs[-1] == "TAA.dst"
    assert not {"Probes", "SVGF", "TAA"} & set(raw.passes) and raw.outputs == ["ToneMap.dst", "Composite.color"]
    assert PRESETS["clean"] == {"gi": "probes", "denoise": "svgf", "taa": True}
    # an option given explicitly overrides the preset's, None included
    assert "Probes" not in rv.graphs.hybrid(gi=None).passes and "SVGF" in rv.graphs.hybrid(gi=None).passes
    g = rv.graphs.hybrid(preset="raw", taa=True)
    assert "TAA" in g.passes and "SVGF" not in g.passes and g.get_pass("GBuffer") is not None
    assert BUILDERS["hybrid"].defaults()["gi"] == "probes" and BUILDERS["hybrid"].defaults("raw")["gi"] is None
    with pytest.raises(OptionError, match=r"hybrid\(preset='cleen'\): unknown preset \(did you mean 'clean'\?\); use 'clean' or 'raw'"):
        rv.graphs.hybrid(preset="cleen")


def test_the_command_line_takes_the_preset_and_overrides_it():
    from rayvr.cli.render import build_graph, resolve_graph_options

    parser = build_parser()

    def graph_of(*argv):
        args = parser.parse_args(["render", *argv])
        resolve_graph_options(args)
        return build_graph(args, 0.0, True, {} if args.gi == "probes" else None)

    assert {"Probes", "SVGF", "TAA"} <= set(graph_of().passes)
    assert not {"Probes", "SVGF", "TAA"} & set(graph_of("--preset", "raw").passes)
    assert set(graph_of("--preset", "raw", "--taa", "on").passes) & {"Probes", "SVGF", "TAA"} == {"TAA"}
    assert "Probes" not in graph_of("--gi", "none").passes
    assert "SVGF" not in graph_of("--graph", "path_traced").passes
