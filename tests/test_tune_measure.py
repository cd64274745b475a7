"""rayvr.tune on the GPU: measure() rows (settings, spread, motion, floors), the displayed image
against the graph's own tone mapper, the probed cost model and tune_effects; the Cornell box at
12x12, one view, a few frames each. Every test builds its own scene (they change effects)."""
import dataclasses
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr import Effect
from rayvr.errors import OptionError
from rayvr.xr.cameras import default_views
from rayvr.study import Config, Display, Motion, ReferenceSettings, StudySettings, measure
from rayvr.study import metrics as M
from rayvr.study.display import to_uint8
from rayvr.tune.cost_probe import ErrorJudge, probe_cost_model

SIZE = (12, 12)
TINY_REF = ReferenceSettings(frames=16, spp=4, max_bounces=4)
TINY = StudySettings(frames=3, timing_frames=1, warmup=1, motion=Motion(frames=3, samples=1), floor_fraction=0.1,
                     progressive_frames=4)


@pytest.fixture
def scene():
    return rv.scenes.cornell_box()


@pytest.fixture(scope="module")
def reference(gpu, tmp_path_factory):
    scene = rv.scenes.cornell_box()
    return rv.tune.cached_reference(scene, default_views(scene, 1, SIZE), TINY_REF, tmp_path_factory.mktemp("ref"),
                                    gpu)


def test_measure_states_settings_spread_motion_and_floor(gpu, scene, reference):
    before = {m.name: m.effect for m in scene.materials}
    configs = [Config("all RASTER", Effect.RASTER, options={"path_bounces": 4}),
               Config("PATH_TRACED 1 spp", Effect.PATH_TRACED, options={"spp": 1, "path_bounces": 4}),
               Config("PATH_TRACED 1 spp x 4 frames", Effect.PATH_TRACED, options={"spp": 1, "path_bounces": 4},
                      accumulate=4)]
    res = measure(scene, configs, views=1, size=SIZE, reference=reference, settings=TINY, cache_dir=False,
                  progress=False, gpu=gpu)
    assert {m.name: m.effect for m in scene.materials} == before                  # effects restored
    raster, pt1, pt4 = (res[c.name] for c in configs)
    for row in (raster, pt1, pt4):
        assert row.gpu_ms == pytest.approx(sum(row.pass_ms.values())) and row.gpu_ms > 0
        assert row.frames == 3 and row.views == 1 and row.size == SIZE
        assert set(row.errors) == set(M.METRICS)
        for stat in row.errors.values():
            assert len(stat["per_view"]) == 1 and stat["std"] >= 0
        assert 0 < row.mean("flip") < 1 and row.mean("relmse") > 0 and 0 < row.mean("ssim") < 1
        assert row.motion["sampled_frames"] == [2] and 0 < row.motion["flip"]["mean"] < 1
        assert {"relmse", "noise_relmse", "bias_relmse", "within_noise", "flip"} <= set(row.floor)
        assert row.image.shape == (1, 12, 12, 4) and row.maps["flip"].shape == (1, 12, 12)
    assert "Shadows" not in raster.pass_ms and "PathTracer" in pt1.pass_ms
    assert pt1.settings["spp"] == 1 and pt1.settings["bounces"] == 4 and pt1.settings["graph"] == "hybrid"
    assert pt4.settings["frames_accumulated"] == 4 and pt1.settings["frames_accumulated"] == 1
    assert pt1.settings["denoiser"] == "none" and pt1.settings["effects"]["Floor"] == "PATH_TRACED"
    assert pt1.errors["relmse"]["std"] > 0                                         # independent frames differ
    assert pt4.mean("relmse") < 0.6 * pt1.mean("relmse")                           # 4 frames averaged: less noise
    # both floors keep the pixel-centre G-buffer's aliasing against the pixel-filtered reference
    # (at 12x12 most of PATH_TRACED's floor); RASTER also leaves out the indirect light
    assert raster.floor["bias_relmse"] > 3 * pt1.floor["bias_relmse"]
    # the first judged image's own metrics are one of the samples the row summarises
    per_view, _ = M.evaluate(pt1.image, reference.image, Display().fixed(reference.image), res.study["ppd"])
    assert pt1.errors["flip"]["mean"] == pytest.approx(per_view["flip"][0], rel=0.5)
    assert res.study["ppd"] == pytest.approx(14.0, abs=0.05) and res.study["timing"] in ("timer-query", "finish+wall")
    curve = res.curves[0]
    assert [p["frames"] for p in curve.points] == [1, 2, 4]
    assert curve.points[-1]["relmse"] < curve.points[0]["relmse"]
    assert all(p["gpu_s"] == pytest.approx(p["frames"] * curve.gpu_ms_per_frame / 1e3) for p in curve.points)


def test_the_displayed_image_is_the_graphs_tone_mapping(gpu, scene):
    """The study's CPU display transform gives the pixels the graph's ToneMapper writes."""
    views = default_views(scene, 1, SIZE)
    graph = rv.tune.path_traced_graph(spp=2, exposure=1.5)
    with rv.Renderer(scene, graph, views=views, gpu=gpu, profiling=False) as r:
        r.render()
        linear = r.read_output("Accumulate.dst", flip_y=True)
        shown = r.read_output("ToneMap.dst", flip_y=True)
    ours = to_uint8(Display("aces", 1.5)(linear))
    assert np.abs(ours.astype(int) - shown[..., :3].astype(int)).max() <= 1
    assert shown[..., :3].max() > 200                       # the light is in the picture, not a black test


def test_taa_negative_radiance_is_judged_as_displayed_and_counted(gpu, scene, reference):
    taa = Config("PATH_TRACED 1 spp + TAA", Effect.PATH_TRACED, graph="hybrid_taa",
                 options={"spp": 1, "path_bounces": 4})
    settings = StudySettings(frames=4, timing_frames=1, warmup=1, motion=None, floors=False, progressive_frames=0)
    row = measure(scene, [taa], views=1, size=SIZE, reference=reference, settings=settings, cache_dir=False,
                  progress=False, gpu=gpu, curves=False).rows[0]
    # TAA's YCoCg box clamp leaves some RGB channels below 0 (40 values here on llvmpipe); HDR-FLIP
    # refuses negative radiance, so without the clamp to what the display shows this would raise
    assert math.isfinite(row.mean("hdrflip")) and row.as_dict()["negative_values"] == row.negative_values


def test_measure_refuses_bad_input(gpu, scene, reference):
    kw = {"views": 1, "size": SIZE, "reference": reference, "settings": TINY, "progress": False, "gpu": gpu}
    with pytest.raises(OptionError, match="1 view\\(s\\) of 12x12, the study renders 2"):
        measure(scene, [Config("r", Effect.RASTER)], **{**kw, "views": 2})
    with pytest.raises(OptionError, match="no material 'Flor'.*did you mean 'Floor'"):
        measure(scene, [Config("r", {"Flor": Effect.RASTER})], **kw)
    with pytest.raises(OptionError, match="unique"):
        measure(scene, [Config("r", Effect.RASTER)] * 2, **kw)
    with pytest.raises(OptionError, match="unknown metric 'mse'"):
        StudySettings(metrics=("mse",))
    with pytest.raises(OptionError, match="accumulate"):
        Config("r", accumulate=0)
    with pytest.raises(OptionError, match="graph 'hybird' is unknown.*did you mean 'hybrid'"):
        Config("r", graph="hybird")


def _judge(reference, metric="relmse"):
    return ErrorJudge(reference, Display().fixed(reference.image), 14.0, metric, M.DEFAULT_EPS)


def test_probed_model_splits_time_and_error_by_material(gpu, scene, reference):
    views = default_views(scene, 1, SIZE)
    judge = _judge(reference)
    model, pin = probe_cost_model(scene, views, rv.tune.hybrid_graph, {"path_bounces": 4}, judge,
                                  levels=[Effect.RASTER, Effect.SHADOWS], frames=1, warmup=1, trials=1,
                                  progress=False, gpu=gpu)
    assert pin == "Composite.color"
    assert set(model.pixels) == set(scene.materials.names())
    assert sum(model.pixels.values()) == SIZE[0] * SIZE[1]               # the box fills the view
    assert model.pixels["BackWall"] > model.pixels["Light"] > 0
    # the level's change of time shared by pixels (its sign is llvmpipe's: direct lighting of every pixel
    # can cost more than 144 pixels' shadow rays)
    shadows = {n: model.ms[n][Effect.SHADOWS] for n in ("BackWall", "Light")}
    assert shadows["BackWall"] != 0.0
    assert shadows["BackWall"] / shadows["Light"] == pytest.approx(model.pixels["BackWall"] / model.pixels["Light"])
    assert all(model.ms[n][Effect.RASTER] == 0 for n in model.materials)
    # per-material shares of the all-RASTER error add up to that image's relMSE (the next frame's)
    settings = StudySettings(frames=1, timing_frames=1, warmup=1, motion=None, floors=False, progressive_frames=0,
                             metrics=("relmse",))
    raster = measure(scene, [Config("r", Effect.RASTER, options={"path_bounces": 4})], views=views,
                     reference=reference, settings=settings, progress=False, gpu=gpu, curves=False)["r"]
    # the two judge different frames where the warm-up is timed (GPUs with timer queries), and
    # RASTER's one light sample per pixel moves relMSE by ~5% from frame to frame (H200: 5.6%)
    assert model.predict_error({n: Effect.RASTER for n in model.materials}) == pytest.approx(
        raster.mean("relmse"), rel=0.1)


def test_tune_effects_fits_the_budget_or_says_why(gpu, scene, reference):
    kw = {"size": SIZE, "views": 1, "levels": [Effect.RASTER, Effect.SHADOWS], "frames": 1, "warmup": 1,
          "trials": 1, "reference": reference, "progress": False, "metric": "relmse", "gpu": gpu,
          "option_sets": [{}]}   # the graph's own options: the next test tries others
    tight = rv.tune.tune_effects(scene, budget_ms=1e-3, apply=False, **kw)
    assert not tight.fits and set(tight.assignment.values()) == {Effect.RASTER}
    assert "exceeds" in tight.notes[0] and tight.measured_ms is not None
    roomy = rv.tune.tune_effects(scene, budget_ms=1e4, apply=True, **kw)
    assert roomy.fits and roomy.predicted_ms <= 1e4
    assert {n: m.effect for n, m in zip(scene.materials.names(), scene.materials)} == roomy.assignment
    for n, e in roomy.assignment.items():   # with unlimited time every upgrade that helps is taken
        assert e == Effect.SHADOWS or roomy.model.error[n][Effect.SHADOWS] >= roomy.model.error[n][Effect.RASTER]


def test_tune_effects_on_a_renderer_uses_its_views_and_graph(gpu, scene, reference):
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=1, size=SIZE) as r:
        with pytest.raises(OptionError, match="brings its own views"):
            rv.tune.tune_effects(r, size=SIZE)
        tuned = rv.tune.tune_effects(r, budget_ms=1e4, levels=[Effect.RASTER, Effect.SHADOWS], frames=1, warmup=1,
                                     trials=1, reference=reference, verify=False, progress=False, metric="relmse")
        assert tuned.measured_ms is None and tuned.fits
        assert {m.name: m.effect for m in scene.materials} == tuned.assignment
        r.render()                                   # the renderer picks the new effects up
        assert ("Shadows" in r.profile().passes) == (Effect.SHADOWS in tuned.assignment.values())


def test_tune_effects_is_still_where_it_was_imported_from():
    from rayvr.tune import tune_effects
    from rayvr.tune.tuner import tune_effects as moved

    assert tune_effects is moved and rv.tune.tune_effects is moved


def test_tune_effects_tries_the_graph_options_and_keeps_what_pays(gpu, scene, reference):
    kw = {"size": SIZE, "views": 1, "levels": [Effect.RASTER, Effect.SHADOWS], "frames": 2, "warmup": 4,
          "trials": 1, "reference": reference, "progress": False, "metric": "relmse", "gpu": gpu, "apply": False,
          "spend": False}   # the choice among option sets alone (spending: the next test)
    both = rv.tune.tune_effects(scene, budget_ms=1e4, option_sets=[{}, {"gi": "probes"}], **kw)
    # the box's indirect light is most of its radiance: the probes cut the error, whatever they cost
    assert both.options == {"gi": "probes"} and "graph options chosen among gi=probes" in both.notes[-1]
    plain = rv.tune.tune_effects(scene, budget_ms=1e4, option_sets=[{}], **kw)
    # (2.1x here with llvmpipe's 4^3 probes, 1.7x with a GPU's default 8^3 over the same two frames)
    assert plain.options == {} and plain.predicted_error > 1.5 * both.predicted_error
    assert both.measured_error < plain.measured_error      # the verification renders with the options
    with pytest.raises(OptionError, match="option_sets: expected dicts"):
        rv.tune.tune_effects(scene, budget_ms=1e4, option_sets=["gi"], **kw)
    from rayvr.tune.tuner import option_sets_for
    assert option_sets_for(rv.tune.path_traced_graph, {"spp": 1}) == [{"spp": 1}, {"spp": 1, "denoise": "svgf"}]
    from rayvr.study.configs import hybrid_graph   # the hybrid takes each, and them together
    base = [{}, {"gi": "probes"}, {"denoise": "svgf"}, {"gi": "probes", "denoise": "svgf"}]
    assert option_sets_for(hybrid_graph, {}) == base + [{**s, "direct": "restir"} for s in base]


def test_tune_effects_spends_the_headroom_where_the_error_falls(gpu, scene, reference):
    """A choice far under its budget raises its knobs while the measured error falls: more light
    samples for the area light's soft shadows lower the measured relMSE."""
    from rayvr.tune.budget import Knob

    kw = {"size": SIZE, "views": 1, "levels": [Effect.SHADOWS], "frames": 2, "warmup": 2, "trials": 2,
          "reference": reference, "progress": False, "metric": "relmse", "gpu": gpu, "apply": False,
          "option_sets": [{}]}
    plain = rv.tune.tune_effects(scene, budget_ms=1e4, spend=False, **kw)
    spent = rv.tune.tune_effects(scene, budget_ms=1e4, knobs=(Knob("light_samples", (1, 4, 16)),), **kw)
    assert spent.options.get("light_samples") in (4, 16) and "spent the budget's headroom" in spent.notes[-1]
    assert spent.measured_error < plain.measured_error
    assert spent.measured_ms <= 1e4


def test_judged_frames_do_not_depend_on_a_timed_warm_up(gpu, scene, reference):
    # a warm-up timed in seconds renders as many frames as the GPU manages; the judged frames (and a
    # temporal method's history before them) must not follow it
    views = default_views(scene, 1, SIZE)
    configs = [Config("svgf", Effect.PATH_TRACED, options={"path_bounces": 4, "denoise": "svgf"})]
    rows = []
    for warmup_s in (0.0, 0.3):
        settings = StudySettings(frames=2, timing_frames=2, warmup=1, warmup_s=warmup_s, motion=None, floors=False,
                                 progressive_frames=0, metrics=("relmse", "psnr"))
        rows.append(measure(scene, configs, views=views, reference=reference, settings=settings, progress=False,
                            gpu=gpu, curves=False)["svgf"])
    assert rows[0].errors == rows[1].errors and rows[0].mean("relmse") > 0


class _Clock:
    """A wall clock that only the fake renderers below advance: the warm-up's decisions then do
    not depend on how busy the machine running the tests is."""

    def __init__(self):
        self.now = 0.0

    def perf_counter(self) -> float:
        return self.now


class _RampingRenderer:
    """A renderer that advances `clock` by each frame's seconds: 10% faster each (a GPU's clocks
    rising) from 8 ms until they reach 1 ms (frame ~20), steady from frame `settles` on; or, with
    `frame_s(t)`, that function's seconds at clock time t."""

    def __init__(self, clock: _Clock, settles: int = 10 ** 6, start_s: float = 0.008, end_s: float = 0.001,
                 frame_s=None):
        import types

        self.clock, self.frames, self.settles, self.start_s, self.end_s = clock, 0, settles, start_s, end_s
        self.frame_s = frame_s
        self.gl = types.SimpleNamespace(finish=lambda: None)

    def render(self):
        if self.frame_s is not None:
            self.clock.now += self.frame_s(self.clock.now)
        else:
            self.clock.now += max(self.end_s, self.start_s * 0.9 ** min(self.frames, self.settles))
        self.frames += 1


def test_warm_up_renders_on_until_the_frame_time_settles(monkeypatch):
    from rayvr.study import timing

    clock = _Clock()
    monkeypatch.setattr(timing, "time", clock)
    monkeypatch.setattr(timing, "SETTLE_WINDOW_S", 0.02)
    monkeypatch.setattr(timing, "MAX_SETTLE_S", 5.0)
    ramp = _RampingRenderer(clock)
    timing.warm_up(ramp, 0.01)
    assert ramp.frames >= 20           # not before the frames stopped getting faster
    steady = _RampingRenderer(clock, settles=0)
    timing.warm_up(steady, 0.01)
    assert steady.frames == 2 + 2 * 3   # a steady 8 ms GPU: the 0.01 s, then two windows of 0.02 s
    monkeypatch.setattr(timing, "MAX_SETTLE_S", 0.1)
    # windows alternately of 1 ms and 3 ms frames: never settles, so the cap ends it
    jumpy = _RampingRenderer(clock, frame_s=lambda t: 0.001 if int(t / 0.02) % 2 else 0.003)
    t0 = clock.now
    timing.warm_up(jumpy, 0.01)
    assert 0.01 + 0.1 <= clock.now - t0 < 0.01 + 0.1 + 0.05     # bounded by the seconds and the cap
    none = _RampingRenderer(clock, settles=0)
    timing.warm_up(none, 0.0)
    assert none.frames == 0            # no warm-up asked (llvmpipe): nothing rendered


def test_a_level_on_every_material_is_predicted_as_the_probe_timed_it(gpu, scene, reference, monkeypatch):
    """Direct lighting shrinks where rays light the pixels instead: the base's passes change with
    the level, and the model shares that change by pixels like the ray passes' time."""
    from rayvr.tune import cost_probe as P
    from rayvr.study.timing import Timing

    frames = iter([{"GBuffer": 1.0, "Direct": 0.5, "Composite": 0.1},                  # all RASTER
                   {"GBuffer": 1.0, "Direct": 0.1, "Shadows": 2.0, "Composite": 0.1}])   # all SHADOWS
    monkeypatch.setattr(P, "timed_frames", lambda *a, **k: (lambda ms: Timing(sum(ms.values()), ms, 0.0, "given",
                                                                              1))(next(frames)))
    views = default_views(scene, 1, SIZE)
    model, _ = probe_cost_model(scene, views, rv.tune.hybrid_graph, {"path_bounces": 4}, _judge(reference),
                                levels=[Effect.RASTER, Effect.SHADOWS], frames=1, warmup=1, trials=1, progress=False,
                                gpu=gpu)
    every = {n: Effect.SHADOWS for n in model.materials}
    assert model.predict_ms(every) == pytest.approx(3.2)      # not 1.6 + 2.0: Direct's 0.4 less counts
    assert model.predict_ms({n: Effect.RASTER for n in model.materials}) == pytest.approx(1.6)
    assert model.ms["BackWall"][Effect.SHADOWS] == pytest.approx(1.6 * model.pixels["BackWall"] / SIZE[0] / SIZE[1])


def test_probe_gi_frames_are_planned_with_their_probe_rays():
    """The progress plan (and so the ETA) counts probe GI's rays per frame, a fixed cost shared by
    the frame's pixels: at 2x32x32 the default 8^3 x 128 rays outweigh the SHADOWS pass 30 times,
    at 2x1440x1600 they add under 2%."""
    from rayvr.scene.builtin import cornell_box
    from rayvr.study.measure import EFFECT_COST, PROBE_RAY_COST, frame_cost

    scene = cornell_box()
    plain = Config("all SHADOWS", Effect.SHADOWS)
    gi = Config("all SHADOWS + probes GI", Effect.SHADOWS, options={"gi": "probes"})
    small = Config("small volume", Effect.SHADOWS, options={"gi": "probes", "probes": {"counts": [2, 2, 2]}})
    assert frame_cost(plain, scene, 2048) == frame_cost(gi, scene) == EFFECT_COST[Effect.SHADOWS]
    assert frame_cost(gi, scene, 2048) == pytest.approx(0.5 + PROBE_RAY_COST * 512 * 128 / 2048)
    assert frame_cost(gi, scene, 2048) > 30 * frame_cost(plain, scene, 2048)
    assert frame_cost(gi, scene, 2 * 1440 * 1600) < 1.02 * frame_cost(plain, scene, 2 * 1440 * 1600)
    assert frame_cost(small, scene, 2048) == pytest.approx(0.5 + PROBE_RAY_COST * 8 * 128 / 2048)


def test_a_tuned_row_over_its_budget_is_chosen_again_and_measured_alone(gpu, scene, reference, monkeypatch):
    """tuned_study with a cost model that promises 1/1.3 of what the (fake) study measures: the
    row tuned for 6 ms (both walls SHADOWS, predicted 5.0, measured 6.5) is chosen again for a
    smaller ask, that choice is measured on its own and replaces the row, and the TuneResult
    records its measurement and what it replaced."""
    import importlib

    from rayvr.tune.budget import CostModel
    from rayvr.study.runner import LocalRunner
    from rayvr.tune.tuner import tuned_study

    R, S = Effect.RASTER, Effect.SHADOWS
    model = CostModel(2.0, {"A": {R: 0, S: 1.5}, "B": {R: 0, S: 1.5}}, {"A": {R: 1.0, S: 0.1}, "B": {R: 1.0, S: 0.2}})

    class Probe(LocalRunner):
        def probe(self, *args, **kwargs):
            return model, "Composite.color"

    class Row:
        def __init__(self, name, effects):
            self.name, self.effects, self.tuned = name, dict(effects), False
            self.gpu_ms = 1.3 * model.predict_ms(self.effects)

        def mean(self, metric):
            return model.predict_error(self.effects)

    class Results:
        method = "fake"

        def __init__(self, rows):
            self.rows, self.tuned = rows, None

        def __getitem__(self, name):
            return next(r for r in self.rows if r.name == name)

    measured = []

    def fake_measure(scene_, configs, **kwargs):
        measured.append(([c.name for c in configs], kwargs.get("curves", True)))
        return Results([Row(c.name, c.effects) for c in configs])

    monkeypatch.setattr(importlib.import_module("rayvr.study.measure"), "measure", fake_measure)
    settings = dataclasses.replace(TINY, metric_workers=0)
    results, tuned = tuned_study(scene, default_views(scene, 1, SIZE), reference, settings, [], budgets=(6.0, 10.0),
                                 progress=False, runner=Probe(), option_sets=[{}], spend=False)
    # the study with its curves, then the backed-off row alone, without them
    assert measured == [(["tuned for 6 ms", "tuned for 10 ms"], True), (["tuned for 6 ms"], False)]
    six, ten = tuned[6.0], tuned[10.0]
    assert six.assignment == {"A": S, "B": R} and results["tuned for 6 ms"].effects == six.assignment
    assert six.measured_ms == pytest.approx(4.55) and six.budget_ms == 6.0
    assert "backed off from a choice predicted 5 ms that measured 6.5" in six.notes[-1]
    assert ten.assignment == {"A": S, "B": S} and ten.measured_ms == pytest.approx(6.5)   # within its budget
    assert all(r.tuned for r in results.rows) and results.tuned is six


def test_a_study_run_again_takes_its_finished_rows_from_the_cache(gpu, scene, tmp_path, monkeypatch):
    """Rows are cached as they finish: a second run of the same study renders none of them (a
    Renderer would fail here), and gives the same rows; another configuration is measured."""
    ref = ReferenceSettings(frames=4, spp=2, max_bounces=2)
    settings = StudySettings(frames=1, timing_frames=1, warmup=1, motion=None, floor_fraction=0.5,
                             progressive_frames=0)
    configs = [Config("all RASTER", Effect.RASTER, options={"path_bounces": 2}),
               Config("all SHADOWS", Effect.SHADOWS, options={"path_bounces": 2})]
    kw = dict(views=1, size=SIZE, reference=ref, settings=settings, cache_dir=tmp_path, progress=False, gpu=gpu,
              curves=False)
    first = measure(scene, configs, **kw)
    assert len(list(tmp_path.glob("row-*.pkl"))) == 2

    def no_render(*args, **kwargs):
        raise AssertionError("a cached row was rendered again")
    with monkeypatch.context() as m:
        m.setattr(rv.renderer.Renderer, "__init__", no_render)
        again = measure(scene, configs, **kw)
    for a, b in zip(first.rows, again.rows):
        assert a.name == b.name and a.gpu_ms == b.gpu_ms and a.errors == b.errors and a.floor == b.floor
        np.testing.assert_array_equal(a.image, b.image)
    other = measure(scene, [Config("all REFLECTIONS", Effect.REFLECTIONS, options={"path_bounces": 2})], **kw)
    assert other.rows[0].name == "all REFLECTIONS" and len(list(tmp_path.glob("row-*.pkl"))) == 3
