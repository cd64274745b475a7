"""rayvr.tune on the GPU: measure(), the cached reference, the probed cost model and tune_effects,
on the Cornell box at 16x16 (a few frames each)."""
import json
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr import Effect
from rayvr.errors import OptionError
from rayvr.tune import Config, ReferenceSettings, measure
from rayvr.tune import metrics as M

SIZE = (16, 16)
TINY_REF = ReferenceSettings(frames=4, spp=1, max_bounces=2)


@pytest.fixture(scope="module")
def scene():
    return rv.scenes.cornell_box()


@pytest.fixture(scope="module")
def reference(gpu, scene, tmp_path_factory):
    views = rv.tune.make_views(scene, 1, SIZE)
    image, path = rv.tune.reference_image(scene, views, TINY_REF, tmp_path_factory.mktemp("refcache"), gpu,
                                          progress=False)
    return image, path


def test_reference_is_cached_by_scene_views_and_settings(gpu, scene, reference, tmp_path):
    image, path = reference
    assert image.shape == (1, SIZE[1], SIZE[0], 4) and image.dtype == np.float32
    assert np.isfinite(image).all() and image[..., :3].max() > 1.0       # the light is seen (emission 17)
    views = rv.tune.make_views(scene, 1, SIZE)
    mtime = path.stat().st_mtime_ns
    again, same = rv.tune.reference_image(scene, views, TINY_REF, path.parent, gpu, progress=False)
    assert same == path and path.stat().st_mtime_ns == mtime and np.array_equal(again, image)
    key = rv.tune.reference.reference_key
    other_views = rv.tune.make_views(scene, 2, SIZE)
    assert key(scene, views, TINY_REF) != key(scene, other_views, TINY_REF)
    assert key(scene, views, TINY_REF) != key(scene, views, ReferenceSettings(frames=5, spp=1, max_bounces=2))
    scene.materials["Floor"].effect = Effect.PATH_TRACED        # effects do not change the reference
    try:
        assert key(scene, views, TINY_REF) == key(rv.scenes.cornell_box(), views, TINY_REF)
    finally:
        scene.materials["Floor"].effect = Effect.SHADOWS


def test_measure_times_passes_and_scores_against_the_reference(gpu, scene, reference, tmp_path):
    ref, _ = reference
    before = {m.name: m.effect for m in scene.materials}
    configs = [Config("raster", Effect.RASTER), Config("shadows", {"*": Effect.RASTER, "TallBox": Effect.SHADOWS})]
    res = measure(scene, configs, reference=ref, size=SIZE, views=1, frames=2, warmup=1, keep_images=True,
                  progress=False)
    assert {m.name: m.effect for m in scene.materials} == before       # effects restored
    raster, shadows = res["raster"], res["shadows"]
    assert res.method in ("timer-query", "finish+wall")
    for row in (raster, shadows):
        assert row.frame_ms == pytest.approx(sum(row.pass_ms.values())) and row.frame_ms > 0
        assert row.errors == pytest.approx(M.all_metrics(row.image, ref))   # independent recomputation
        assert 0 < row.errors["flip"] < 1 and row.errors["relmse"] > 0 and math.isfinite(row.errors["psnr"])
    assert "Shadows" not in raster.pass_ms and "Shadows" in shadows.pass_ms   # pruned without SHADOWS
    assert shadows.effects["TallBox"] == "SHADOWS" and shadows.effects["Floor"] == "RASTER"

    # against its own image a configuration has no error (rendering is deterministic per frame)
    own = measure(scene, [Config("raster", Effect.RASTER)], reference=raster.image, size=SIZE, views=1,
                  frames=2, warmup=1, progress=False)["raster"]
    assert own.errors["flip"] == 0.0 and own.errors["relmse"] == 0.0 and own.errors["psnr"] == math.inf

    paths = res.write(tmp_path / "report", budget_ms=5.0)
    names = sorted(p.name for p in paths)
    assert names == ["error_vs_ms_flip.png", "error_vs_ms_psnr.png", "error_vs_ms_relmse.png", "results.csv",
                     "results.json", "table.md"]
    doc = json.loads((tmp_path / "report" / "results.json").read_text())
    assert [c["name"] for c in doc["configurations"]] == ["raster", "shadows"]
    assert doc["info"]["method"] == res.method
    assert (tmp_path / "report" / "error_vs_ms_flip.png").read_bytes()[:4] == b"\x89PNG"
    assert "| shadows |" in res.table() and res.to_csv().splitlines()[0].startswith("configuration,frame_ms,flip")
    assert not list((tmp_path / "report").glob(".*"))                   # no temporary files left
    loaded = rv.tune.Results.load(tmp_path / "report" / "results.json")
    assert loaded.table() == res.table() and loaded["shadows"].pass_ms == shadows.pass_ms
    with pytest.raises(OptionError, match="not a rayvr.tune results.json"):
        rv.tune.Results.load(tmp_path / "report" / "table.md")


def test_measure_refuses_bad_input(gpu, scene, reference):
    ref, _ = reference
    with pytest.raises(OptionError, match="1 view\\(s\\) of 16x16, but the measurement renders 2"):
        measure(scene, [Config("r", Effect.RASTER)], reference=ref, size=SIZE, views=2, progress=False)
    with pytest.raises(OptionError, match="no material 'Flor'.*did you mean 'Floor'"):
        measure(scene, [Config("r", {"Flor": Effect.RASTER})], reference=ref, size=SIZE, views=1, progress=False)
    with pytest.raises(OptionError, match="unknown metric 'ssim'"):
        measure(scene, [Config("r", Effect.RASTER)], reference=ref, size=SIZE, views=1, metrics=("ssim",),
                progress=False)
    with pytest.raises(OptionError, match="unique"):
        measure(scene, [Config("r", Effect.RASTER)] * 2, reference=ref, size=SIZE, views=1, progress=False)
    bad = ref.copy()
    bad[0, 2, 3, 1] = np.nan
    with pytest.raises(rv.RayvrError, match="reference: 1 NaN/Inf"):
        measure(scene, [Config("r", Effect.RASTER)], reference=bad, size=SIZE, views=1, frames=1, warmup=1,
                progress=False)


def test_probed_model_splits_time_and_error_by_material(gpu, scene, reference):
    ref, _ = reference
    views = rv.tune.make_views(scene, 1, SIZE)
    model, _, pin = rv.tune.probe_cost_model(scene, views, rv.tune.hybrid_graph, {}, metric="relmse",
                                             levels=[Effect.RASTER, Effect.SHADOWS], frames=2, warmup=1,
                                             reference=ref, progress=False)
    assert pin == "Composite.color"
    assert set(model.pixels) == set(scene.materials.names())
    assert sum(model.pixels.values()) == SIZE[0] * SIZE[1]               # the box fills the view
    assert model.pixels["BackWall"] > model.pixels["Light"] > 0
    # per-material shares of the all-RASTER error add up to that image's relMSE exactly
    raster = measure(scene, [Config("r", Effect.RASTER)], reference=ref, views=views, frames=2, warmup=1,
                     progress=False)["r"]
    assert model.predict_error({n: Effect.RASTER for n in model.materials}) == pytest.approx(
        raster.errors["relmse"], rel=1e-5)
    only = measure(scene, [Config("r", Effect.RASTER)], reference=ref, views=views, frames=2, warmup=1,
                   metrics=("relmse",), progress=False)
    assert only["r"].errors == {"relmse": pytest.approx(raster.errors["relmse"])} and only.metrics() == ["relmse"]
    # ray time is shared by pixel count: bigger materials cost more
    assert model.ms["BackWall"][Effect.SHADOWS] > model.ms["Light"][Effect.SHADOWS] > 0
    assert all(model.ms[n][Effect.RASTER] == 0 for n in model.materials)


def test_tune_effects_fits_the_budget_or_says_why(gpu, scene, reference):
    ref, _ = reference
    kw = {"size": SIZE, "views": 1, "levels": [Effect.RASTER, Effect.SHADOWS], "frames": 2, "warmup": 1,
          "reference": ref, "progress": False}
    tight = rv.tune.tune_effects(scene, budget_ms=1e-3, apply=False, **kw)
    assert not tight.fits and set(tight.assignment.values()) == {Effect.RASTER}
    assert "exceeds" in tight.notes[0] and tight.measured_ms is not None
    roomy = rv.tune.tune_effects(scene, budget_ms=1e4, apply=True, **kw)
    assert roomy.fits and roomy.predicted_ms <= 1e4
    assert {n: m.effect for n, m in zip(scene.materials.names(), scene.materials)} == roomy.assignment
    for n, e in roomy.assignment.items():   # with unlimited time every upgrade that helps is taken
        assert e == Effect.SHADOWS or roomy.model.error[n][Effect.SHADOWS] >= roomy.model.error[n][Effect.RASTER]
    for m in scene.materials:
        m.effect = Effect.SHADOWS


def test_tune_effects_on_a_renderer_uses_its_views_and_graph(gpu, scene, reference):
    ref, _ = reference
    with rv.Renderer(scene, rv.graphs.hybrid(), views=1, size=SIZE) as r:
        with pytest.raises(OptionError, match="brings its own views"):
            rv.tune.tune_effects(r, size=SIZE)
        tuned = rv.tune.tune_effects(r, budget_ms=1e4, levels=[Effect.RASTER, Effect.SHADOWS], frames=1, warmup=1,
                                     reference=ref, verify=False, progress=False)
        assert tuned.measured_ms is None and tuned.fits
        assert {m.name: m.effect for m in scene.materials} == tuned.assignment
        r.render()                                   # the renderer picks the new effects up
        assert ("Shadows" in r.profile().passes) == (Effect.SHADOWS in tuned.assignment.values())
    for m in scene.materials:
        m.effect = Effect.SHADOWS
