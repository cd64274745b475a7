"""OIDN (rayvr.passes.OIDNDenoise, the `oidn` extra) and the denoiser's front ends: it lowers the
error of a 4-spp render, `rayvr render --denoise none|svgf|oidn`, the one line without pyoidn,
and the error study's denoiser rows."""
import sys

import numpy as np
import pytest

import rayvr as rv
from rayvr.cli.main import main
from rayvr.errors import OptionError
from rayvr.renderer import Renderer
from rayvr.scene import builtin

pyoidn = pytest.importorskip("pyoidn", reason="the OIDN tests need pyoidn: pip install -e '.[oidn]'")


def rel_mse(image, reference):
    return float(np.mean((image - reference) ** 2 / (reference ** 2 + 1e-2)))


def test_oidn_lowers_the_error_of_a_4_spp_render(gpu):
    """48x48: OIDN's network needs some context (at 12x12 and 32x32 it makes this image worse)."""
    scene, size = builtin.cornell_box(), (48, 48)
    reference_graph = rv.graphs.path_traced(samples_per_pixel=16)
    reference_graph.update_pass("PathTracer", {"pixel_jitter": False})
    with Renderer(scene, reference_graph, size=size, first_frame=1 << 24) as r:
        for _ in range(16):
            r.render()
        reference = r.read_output("Accumulate.dst")[..., :3].astype(np.float64)
    g = rv.graphs.path_traced(samples_per_pixel=4, denoise="oidn")
    g.update_pass("PathTracer", {"pixel_jitter": False})
    with Renderer(scene, g, size=size) as r:
        r.render()
        raw = r.read_output("Accumulate.dst")[..., :3].astype(np.float64)
        denoised = r.read_output("Denoise.dst")[..., :3].astype(np.float64)
        assert r.compiled.plan.order == ["GBuffer", "PathTracer", "Accumulate", "Denoise", "ToneMap"]
    assert rel_mse(denoised, reference) < rel_mse(raw, reference) / 2   # measured 0.011 against 0.042


def test_disabled_oidn_passes_the_colour_through(gpu):
    scene = builtin.cornell_box()
    with Renderer(scene, rv.graphs.path_traced(denoise="oidn"), size=(16, 16)) as r:
        r.compiled.passes["Denoise"].set_properties({"enabled": False})
        r.render()
        np.testing.assert_array_equal(r.read_output("Denoise.dst"), r.read_output("Accumulate.dst"))


def run_render(capsys, *argv):
    code = main(["render", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_render_denoise_options_write_the_denoised_images(gpu, tmp_path, capsys, monkeypatch):
    calls = []
    real = pyoidn.denoise
    monkeypatch.setattr(pyoidn, "denoise", lambda *a, **k: calls.append(1) or real(*a, **k))
    images = {}
    for denoise in ("none", "svgf", "oidn"):
        out = tmp_path / f"{denoise}.exr"
        code, text, err = run_render(capsys, "--size", "16x16", "--frames", "3", "--effect", "*=path_traced",
                                     "--preset", "raw", "--denoise", denoise, "--out", str(out))
        assert code == 0, err
        assert ("SVGF" in text) == (denoise == "svgf") and ("Denoise" in text) == (denoise == "oidn")
        import OpenEXR

        with OpenEXR.File(str(tmp_path / f"{denoise}_L.exr")) as f:
            images[denoise] = np.asarray(f.channels()["RGB"].pixels, np.float64)
    assert len(calls) == 2          # OIDN on the last of the 3 frames only, once per eye
    noisy = np.abs(np.diff(images["none"], axis=1)).mean()
    assert np.abs(np.diff(images["svgf"], axis=1)).mean() < noisy / 2
    # OIDN at 16x16 has little context (its quality is tested at 48x48 above): the written image
    # is the denoised one, smoother than the input
    assert not np.array_equal(images["oidn"], images["none"])
    assert np.abs(np.diff(images["oidn"], axis=1)).mean() < noisy


def test_denoise_oidn_without_pyoidn_is_one_line_and_exit_2(gpu, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyoidn", None)   # import pyoidn now raises ImportError
    code, out, err = run_render(capsys, "--size", "8x8", "--denoise", "oidn", "--out", str(tmp_path / "x.png"))
    assert code == 2 and not list(tmp_path.iterdir())
    line = err.strip()
    assert "\n" not in line and "--denoise oidn" in line and "pip install 'rayvr[oidn]'" in line
    with pytest.raises(OptionError, match=r"rayvr\[oidn\]"):
        rv.graphs.path_traced(denoise="oidn")
    assert rv.study.configs.available_denoisers() == ["svgf"]   # the study leaves OIDN's rows out


def test_the_error_study_gets_denoiser_rows(gpu):
    from rayvr.study.configs import available_denoisers, path_traced_graph

    assert available_denoisers() == ["svgf", "oidn"] and available_denoisers(path_traced_graph) == ["svgf", "oidn"]
    scene = builtin.cornell_box()
    names = [c.name for c in rv.tune.standard_configs(scene, spp=(1, 4))]
    for name in ("PATH_TRACED 1 spp + SVGF", "PATH_TRACED 4 spp + SVGF", "PATH_TRACED 1 spp + OIDN"):
        assert name in names
    svgf = next(c for c in rv.tune.standard_configs(scene, spp=(1,)) if c.name.endswith("+ SVGF"))
    graph = svgf.build_graph()
    assert svgf.settings(scene)["denoiser"] == "svgf" and svgf.output_pin(graph) == "TAA.dst"
    oidn = next(c for c in rv.tune.standard_configs(scene, spp=(1,)) if c.name.endswith("+ OIDN"))
    assert oidn.output_pin(oidn.build_graph()) == "Denoise.dst"
    settings = rv.tune.StudySettings(frames=2, timing_frames=1, warmup=0, motion=None, floors=False,
                                     progressive_frames=0)
    reference = rv.tune.ReferenceSettings(frames=4, spp=2, max_bounces=2)
    res = rv.study.measure(scene, [svgf, oidn], views=1, size=(12, 12), reference=reference, settings=settings,
                          cache_dir=False, progress=False, gpu=gpu)
    for config in (svgf, oidn):
        row = res[config.name]
        assert row.gpu_ms > 0 and np.isfinite(row.errors["relmse"]["mean"])
    assert "SVGF" in res[svgf.name].pass_ms and "Denoise" in res[oidn.name].pass_ms


def test_denoise_benchmark_smoke_run(gpu, tmp_path):
    import argparse
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))   # the repository root holds benchmarks/
    from benchmarks import denoise

    parser = argparse.ArgumentParser()
    denoise.add_arguments(parser)
    args = parser.parse_args(["--scenes", "cornell_box", "--time-sizes", "2x8x8", "--size", "8x8",
                              "--reference-frames", "2", "--reference-spp", "1", "--motion-frames", "2",
                              "--motion-samples", "1", "--frames", "1", "--timing-frames", "1", "--warmup", "0",
                              "--cache", str(tmp_path)])
    args.quick = True
    result = denoise.run(args)
    rows = [dict(zip(result["columns"], row)) for row in result["rows"]]
    assert [r["part"] for r in rows] == ["time"] + ["error"] * 6
    assert rows[0]["SVGF ms"] > 0 and rows[0]["SVGF MB"] > 0
    svgf = next(r for r in rows if r["config"] == "PATH_TRACED 1 spp + SVGF")
    assert svgf["SVGF ms"] > 0 and svgf["FLIP"] != "-" and svgf["FLIP in motion"] != "-"


def test_denoise_benchmark_times_each_svgf_kernel(gpu):
    import argparse
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))   # the repository root holds benchmarks/
    from benchmarks import denoise

    parser = argparse.ArgumentParser()
    denoise.add_arguments(parser)
    args = parser.parse_args(["--scenes", "cornell_box", "--time-sizes", "2x8x8", "--parts", "time",
                              "--kernels", "3,5,3:6", "--timing-frames", "1", "--warmup", "0"])
    args.quick = True
    rows = [dict(zip(r["columns"], row)) for r in [denoise.run(args)] for row in r["rows"]]
    assert [r["config"] for r in rows] == ["1 spp + SVGF 3x3 + TAA (1 bounce)", "1 spp + SVGF 5x5 + TAA (1 bounce)",
                                           "1 spp + SVGF 3x3 x6 + TAA (1 bounce)"]
    assert all(r["SVGF ms"] > 0 and r["SVGF MB"] > 0 for r in rows)
    for bad in ("4", "3:9", "5x5", "3:"):
        args.kernels = bad
        with pytest.raises(OptionError, match="--kernels"):
            denoise.run(args)


def test_the_error_study_gets_the_hybrid_levels_through_svgf_with_and_without_probe_gi(gpu):
    scene = builtin.cornell_box()
    configs = {c.name: c for c in rv.tune.standard_configs(scene, spp=(1,))}
    for level in ("all RASTER", "all SHADOWS", "all REFLECTIONS", "SHADOWS + REFLECTIONS (Floor)"):
        assert f"{level} + SVGF" in configs and f"{level} + probes GI + SVGF" in configs
        assert f"{level} + OIDN" not in configs          # offline: no frame budget to trade
    both = configs["all SHADOWS + probes GI + SVGF"]
    graph = both.build_graph()
    assert {"SVGF", "Probes", "Shadows"} <= set(graph.passes) and both.output_pin(graph) == "TAA.dst"
    assert both.settings(scene)["denoiser"] == "svgf" and both.settings(scene)["gi"] == "probes"
    assert not any(n.endswith("SVGF") and not n.startswith("PATH")
                   for n in (c.name for c in rv.tune.standard_configs(scene, spp=(1,), denoised_levels=False)))
    settings = rv.tune.StudySettings(frames=2, timing_frames=1, warmup=0, motion=None, floors=False,
                                     progressive_frames=0)
    reference = rv.tune.ReferenceSettings(frames=4, spp=2, max_bounces=2)
    res = rv.study.measure(scene, [both, configs["all SHADOWS + probes GI"]], views=1, size=(12, 12),
                          reference=reference, settings=settings, cache_dir=False, progress=False, gpu=gpu)
    denoised, raw = res["all SHADOWS + probes GI + SVGF"], res["all SHADOWS + probes GI"]
    assert denoised.gpu_ms > 0 and np.isfinite(denoised.errors["relmse"]["mean"])
    assert denoised.errors["flip"]["mean"] != raw.errors["flip"]["mean"]     # another image, not the raw one
