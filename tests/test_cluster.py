"""rayvr.cluster on a local Ray with two llvmpipe workers: a 4-view grid split by views equals one
process's render, a reference split by samples agrees with one process (the same paths) and
statistically across seeds, sequences split by frames, the error study split by configuration,
the host-local frame split, workers killed mid-job, Ctrl-C, and `--workers` on the CLI."""
import re

import numpy as np
import pytest
from PIL import Image

import rayvr as rv
import rayvr.cluster as rc
from rayvr.cli.main import main
from rayvr.xr.cameras import default_views

ray = pytest.importorskip("ray", reason="the cluster tests need Ray: pip install -e '.[test,cluster]'")

SIZE = (24, 24)


def shadows_scene():
    """box_on_plane with SHADOWS everywhere: a point light, so no pass draws random numbers."""
    scene = rv.scenes.box_on_plane()
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    return scene


def one_process(scene, graph, views, pins, frames=1):
    with rv.Renderer(scene, graph, views=views) as r:
        for _ in range(frames):
            r.render()
        return {pin: r.read_output(pin, flip_y=True) for pin in pins}


PT = {"spp": 1, "max_bounces": 3}        # the reference graph of these tests: rv.tune.path_traced_graph(**PT)


# -- split by views ----------------------------------------------------------------------------------
def test_four_view_grid_split_by_views_equals_one_process(cluster):
    scene = shadows_scene()
    views = default_views(scene, 4, SIZE, grid=(2, 2))
    pins = ["Composite.color", "ToneMap.dst"]
    got = rc.render_views(scene, rv.graphs.hybrid(preset="raw"), views, pins=pins, cluster=cluster, progress=False)
    want = one_process(scene, rv.graphs.hybrid(preset="raw"), views, pins)
    assert len(got.shares) == 2 and {s["worker"] for s in got.shares} == set(got_workers(cluster))
    for pin in pins:
        assert got.pixels[pin].dtype == want[pin].dtype
        assert np.array_equal(got.pixels[pin], want[pin]), pin
    assert want["ToneMap.dst"].max() > 0


def got_workers(cluster):
    return [ray.get(h.describe.remote()) for h in cluster.handles]


def test_random_passes_split_by_views_are_exact(cluster):
    # The Cornell box's area light is sampled per pixel, seeded by the view's index in the whole
    # frame (views.glsl view_global_index): every share draws the frame's own random numbers.
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 4, SIZE)
    got = rc.render_views(scene, rv.graphs.hybrid(preset="raw"), views, pins=["Composite.color"], cluster=cluster,
                          progress=False).pixels["Composite.color"]
    want = one_process(scene, rv.graphs.hybrid(preset="raw"), views, ["Composite.color"])["Composite.color"]
    assert np.array_equal(got, want)


# -- split by samples --------------------------------------------------------------------------------
def test_reference_split_by_samples_is_one_process_paths_and_reruns_identically(cluster, gpu):
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 2, SIZE)
    one = rv.tune.render_reference(scene, views, rv.tune.ReferenceSettings(8, 1, 3), gpu=gpu)
    ref = rc.converge_reference(scene, views, frames=8, spp=1, max_bounces=3, cluster=cluster, progress=False)
    assert ref.shares == 8 and ref.samples_per_pixel == 8 and len(set(ref.workers)) == 2
    assert np.allclose(ref.image, one.image, rtol=1e-5, atol=1e-6)
    # the study's halves and checks: the same frames as one process, so the same verdict
    assert np.allclose(ref.half_a, one.half_a, rtol=1e-5, atol=1e-6)
    assert np.allclose(ref.half_b, one.half_b, rtol=1e-4, atol=1e-5)
    assert ref.first_frame == one.first_frame == rv.study.seeds.reference_first_frame()
    assert ref.noise_relmse == pytest.approx(one.noise_relmse, rel=1e-3)
    assert ref.bounce_change == pytest.approx(one.bounce_change, rel=1e-3, abs=1e-6) and ref.bounce_change > 0
    # the same verdict; only the wall time it quotes ("8 frames x 1 spp in 3 s") may differ
    def judged(r):
        return re.sub(r" in \d+ s\b", "", r.verdict())
    assert judged(ref) == judged(one) and judged(ref) != ref.verdict()
    again = rc.converge_reference(scene, views, frames=8, spp=1, max_bounces=3, cluster=cluster, progress=False)
    assert np.array_equal(again.image, ref.image)


def test_split_reference_shares_the_study_cache(cluster, gpu, tmp_path):
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 1, SIZE)
    settings = rv.tune.ReferenceSettings(4, 1, 3)
    split = rc.converge_reference(scene, views, settings=settings, cache_dir=tmp_path, cluster=cluster,
                                  progress=False)
    cached = list(tmp_path.glob("*.npz"))
    assert len(cached) == 1 and split.source == str(cached[0])
    here = rv.tune.cached_reference(scene, views, settings, tmp_path, gpu)    # one process finds it
    assert here.source == str(cached[0]) and here.seconds == 0.0
    assert np.array_equal(here.image, split.image) and np.allclose(here.half_b, split.half_b, atol=1e-6)
    again = rc.converge_reference(scene, views, settings=settings, cache_dir=tmp_path, cluster=cluster,
                                  progress=False)
    assert again.shares == 0 and np.array_equal(again.image, split.image)   # from the cache, no render


def test_independent_seeds_agree_within_standard_errors_and_variance_falls_as_one_over_n(cluster):
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 2, SIZE)

    def run(seed, frames):
        return rc.converge_reference(scene, views, frames=frames, **PT, seed=seed, cluster=cluster, progress=False)

    a8, b8, a32, b32 = run(1, 8), run(2, 8), run(3, 32), run(4, 32)
    d8 = (a8.image - b8.image)[..., :3].astype(np.float64)
    d32 = (a32.image - b32.image)[..., :3].astype(np.float64)
    for d, a, b in ((d8, a8, b8), (d32, a32, b32)):
        var = (a.stderr[..., :3].astype(np.float64) ** 2 + b.stderr[..., :3] ** 2)
        pixels = var.shape[0] * var.shape[1] * var.shape[2]
        se = np.sqrt(var.reshape(-1, 3).sum(axis=0)) / pixels            # s.e. of each channel's image mean
        assert np.all(np.abs(d.reshape(-1, 3).mean(axis=0)) < 4 * se), (d.reshape(-1, 3).mean(axis=0), se)
        # batch-means errors are honest or conservative: the shares' pixel-filtered paths are one
        # stratified Sobol sequence, which batch means take for independent batches
        assert 0.5 < var.mean() / (d ** 2).mean() < 6.0
    # 4x the samples: 1/4 of the variance or less (stratified sub-pixel positions at the edges fall faster)
    assert 2.5 < (d8 ** 2).mean() / (d32 ** 2).mean() < 20.0


# -- split by frames and by configurations ---------------------------------------------------------------
def test_sequence_split_into_chunks_equals_one_chunk(cluster):
    scene = rv.scenes.cornell_box()     # random numbers follow the absolute frame index: exact anyway
    seq = rc.TrajectoryViews(default_views(scene, 2, SIZE), "turn", frames=8, fps=30)
    seen = []
    split = rc.render_sequence(scene, rv.graphs.hybrid(preset="raw"), seq, pins=["Composite.color"], chunk=2, warmup=1,
                               on_frame=lambda i, f: seen.append(i), cluster=cluster, progress=False)
    whole = rc.render_sequence(scene, rv.graphs.hybrid(preset="raw"), seq, pins=["Composite.color"], chunk=8,
                               cluster=cluster, progress=False)
    assert seen == list(range(8)) and len(split.chunks) == 4 and len(whole.chunks) == 1
    a, b = split.frames["Composite.color"], whole.frames["Composite.color"]
    assert a.shape == (8, 2, SIZE[1], SIZE[0], 4) and np.array_equal(a, b)
    assert not np.array_equal(a[0], a[4])          # the head turned


def test_error_study_split_by_configuration_matches_one_process(cluster, gpu, tmp_path):
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 2, SIZE)
    ref_settings = rv.tune.ReferenceSettings(4, 1, 3)
    ref = rv.tune.render_reference(scene, views, ref_settings, gpu=gpu)
    configs = rv.tune.standard_configs(scene, ref_settings, spp=(1,), denoised_levels=False)
    settings = rv.tune.StudySettings(frames=1, timing_frames=1, warmup=1, metrics=("relmse", "psnr"),
                                     motion=rv.tune.Motion(frames=2, samples=1), progressive_frames=2)
    kw = {"reference": ref, "views": views, "settings": settings}
    split = rc.measure(scene, configs, cluster=cluster, progress=False, cache_dir=tmp_path / "split", **kw)
    here = rv.study.measure(scene, configs, progress=False, gpu=gpu, cache_dir=tmp_path / "here", **kw)
    assert [r.name for r in split.rows] == [c.name for c in configs]

    def stats(errors):
        return {(m, k): v[k] for m, v in errors.items() for k in ("mean", "std")}

    for a, b in zip(split.rows, here.rows):
        # the study's seeds: the same frames, judged against the same reference
        assert stats(a.errors) == pytest.approx(stats(b.errors), rel=1e-12), a.name
        assert a.floor["relmse"] == pytest.approx(b.floor["relmse"], rel=1e-12)
        assert a.floor["within_noise"] == b.floor["within_noise"]
        # in motion each is judged against its own trajectory reference: the split one's frames are
        # one process's, merged in another order (float rounding only, far inside the noise)
        assert a.motion["relmse"]["mean"] == pytest.approx(b.motion["relmse"]["mean"], rel=1e-3)
        assert a.timed_on and a.timed_on.startswith("worker") and a.gpu_ms > 0 and b.timed_on is None
    assert "timed on" in split.table() and len(split.study["workers"]) == 2
    assert "timed on" not in here.table() and here.study["workers"] == []
    assert [c.name for c in split.curves] == [c.name for c in here.curves] and split.curves[0].timed_on
    # the floors rendered on the workers went into the driver's cache, as one process stores them
    assert sorted(p.name for p in (tmp_path / "split").glob("floor-*.npz")) == \
        sorted(p.name for p in (tmp_path / "here").glob("floor-*.npz")) != []
    assert split.as_dict()["rows"][0]["timed_on"] == split.rows[0].timed_on


# -- one frame over the host's GPUs -------------------------------------------------------------------------
def test_host_split_gathers_exact_pixels_and_balances_a_skewed_start(cluster):
    scene = shadows_scene()
    views = default_views(scene, 4, (64, 64))
    want = one_process(scene, rv.graphs.hybrid(preset="raw"), views, ["Composite.color"])["Composite.color"]
    with rc.HostFrameSplitter(scene, rv.graphs.hybrid(preset="raw"), views, pin="Composite.color", cluster=cluster,
                              initial_shares=[1, 3]) as split:
        timings = [split.render() for _ in range(8)]
        assert np.array_equal(split.pixels(), want)
    assert timings[0].shares == [1, 3]
    assert [2, 2] in [t.shares for t in timings]                 # measured speeds even the shares out
    for t in timings:
        assert t.latency_ms >= max(t.arrival_ms) >= max(t.render_ms) > 0 and t.copy_ms > 0


# -- faults and Ctrl-C ---------------------------------------------------------------------------------------
def test_worker_exiting_mid_share_is_rerun_with_the_same_result(cluster):
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 2, SIZE)
    clean = rc.converge_reference(scene, views, frames=8, **PT, cluster=cluster, progress=False)
    ray.get(cluster.handles[0].fail_after.remote(1))     # os._exit in its next share's first frame
    faulty = rc.converge_reference(scene, views, frames=8, **PT, cluster=cluster, progress=False)
    assert np.array_equal(faulty.image, clean.image)
    assert cluster.size == 2                              # replaced


def test_killed_worker_views_rerun_elsewhere(cluster):
    scene = shadows_scene()
    views = default_views(scene, 4, SIZE)
    victim = cluster.handles[1]
    ray.kill(victim)
    got = rc.render_views(scene, rv.graphs.hybrid(preset="raw"), views, pins=["Composite.color"], cluster=cluster,
                          progress=False)
    want = one_process(scene, rv.graphs.hybrid(preset="raw"), views, ["Composite.color"])
    assert np.array_equal(got.pixels["Composite.color"], want["Composite.color"])
    with pytest.raises(ray.exceptions.RayActorError):
        ray.get(victim.ping.remote())


def test_ctrl_c_stops_the_busy_workers_and_the_next_job_runs(cluster, monkeypatch):
    """Ctrl-C arrives while the driver waits on the busy workers (the third poll: every share in
    flight). Raised from the wait itself, not by a timer's simulated SIGINT, whose delivery
    depended on what else the process had run (it went unseen in full-suite runs)."""
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 2, SIZE)
    busy = list(cluster.handles)
    ray = cluster._ray
    wait, polls = ray.wait, []

    def interrupted_wait(*args, **kwargs):
        polls.append(1)
        if len(polls) == 3:
            raise KeyboardInterrupt
        return wait(*args, **kwargs)

    monkeypatch.setattr(ray, "wait", interrupted_wait)
    with pytest.raises(KeyboardInterrupt):
        rc.converge_reference(scene, views, frames=20000, **PT, cluster=cluster, progress=False)
    monkeypatch.setattr(ray, "wait", wait)
    for handle in busy:
        with pytest.raises(ray.exceptions.RayActorError):
            ray.get(handle.ping.remote(), timeout=30)
    ref = rc.converge_reference(scene, views, frames=2, **PT, cluster=cluster, progress=False)
    assert np.isfinite(ref.image).all() and cluster.size == 2


def test_progress_bar_aggregates_the_workers(cluster, capsys):
    scene = shadows_scene()
    rc.render_views(scene, rv.graphs.hybrid(preset="raw"), default_views(scene, 4, SIZE), frames=3, cluster=cluster,
                    progress=True)
    err = capsys.readouterr().err
    assert "views box_on_plane" in err and "12/12" in err      # 4 views x 3 frames over both workers


# -- the command line ------------------------------------------------------------------------------------------
def test_render_with_workers_writes_one_process_images_and_quilt(cluster, tmp_path, capsys):
    common = ["render", "box_on_plane", "--views", "4", "--grid", "2x2", "--size", "24x24", "--effect", "*=shadows"]
    assert main(common + ["--out", str(tmp_path / "here.png"), "--quilt", str(tmp_path / "qh.png")]) == 0
    code = main(common + ["--workers", "2", "--out", str(tmp_path / "split.png"), "--quilt", str(tmp_path / "qs.png")])
    out = capsys.readouterr().out
    assert code == 0 and "2 worker share(s)" in out
    for i in range(4):
        assert np.array_equal(np.asarray(Image.open(tmp_path / f"split_v{i}.png")),
                              np.asarray(Image.open(tmp_path / f"here_v{i}.png")))
    here_q = [p for p in tmp_path.iterdir() if p.name.startswith("qh")]
    split_q = [p for p in tmp_path.iterdir() if p.name.startswith("qs")]
    assert len(here_q) == len(split_q) == 1
    assert np.array_equal(np.asarray(Image.open(here_q[0])), np.asarray(Image.open(split_q[0])))


def test_converge_with_and_without_workers_share_the_cache_and_the_table(cluster, tmp_path, capsys):
    import json

    tiny = ["--size", "12x12", "--views", "1", "--frames", "1", "--timing-frames", "1", "--warmup", "1",
            "--reference-frames", "4", "--reference-spp", "1", "--bounces", "2", "--motion-frames", "2",
            "--motion-samples", "1", "--progressive-frames", "2", "--spp", "1", "--quiet",
            "--cache", str(tmp_path / "cache")]
    assert main(["converge", *tiny, "--workers", "2", "--report", str(tmp_path / "split")]) == 0
    out = capsys.readouterr().out
    configs = len(json.loads((tmp_path / "split" / "results.json").read_text())["rows"])
    assert configs >= 6 and "timed on" in out and out.count("| worker ") == configs
    cached = sorted((tmp_path / "cache").glob("*.npz"))
    assert len(cached) == 2 + configs                    # the static and trajectory references, a floor each
    assert main(["converge", *tiny, "--report", str(tmp_path / "here")]) == 0
    assert "timed on" not in capsys.readouterr().out
    assert sorted((tmp_path / "cache").glob("*.npz")) == cached      # nothing rendered again
    assert len(list((tmp_path / "cache").glob("row-*.pkl"))) == configs   # the rows measured here, cached
    split, here = (json.loads((tmp_path / d / "results.json").read_text()) for d in ("split", "here"))
    assert here["reference"]["source"] == split["reference"]["source"] in map(str, cached)
    for a, b in zip(split["rows"], here["rows"]):
        assert a["name"] == b["name"] and a["timed_on"].startswith("worker") and b["timed_on"] is None
        for m in ("flip", "relmse"):
            assert a[m]["mean"] == pytest.approx(b[m]["mean"], rel=1e-12)
            assert a["motion"][m]["mean"] == pytest.approx(b["motion"][m]["mean"], rel=1e-12)
        assert a["floor"]["relmse"] == pytest.approx(b["floor"]["relmse"], rel=1e-12)


def test_tune_with_workers_names_the_worker_of_each_row(cluster, tmp_path, capsys):
    code = main(["tune", "--views", "1", "--size", "16x16", "--frames", "1", "--warmup", "1", "--reference-frames", "4",
                 "--reference-spp", "1", "--spp", "1", "--metrics", "relmse", "--metric", "relmse", "--quiet",
                 "--graph-options", "none", "--cache", str(tmp_path / "cache"), "--workers", "2"])
    out = capsys.readouterr().out
    assert code == 0 and "timed on" in out and out.count("| worker ") >= 5
    assert list((tmp_path / "cache").glob("*.npz"))      # the split reference went into tune's cache
