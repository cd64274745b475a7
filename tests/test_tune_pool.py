"""rayvr.study.pool: the error study's metrics in worker processes give the numbers the serial
path gives (the same evaluate, the same inputs), the study's rows too; the progress bar counts
the workers' seconds over the workers."""
import os

import numpy as np
import pytest

import rayvr as rv
from rayvr import Effect
from rayvr.xr.cameras import default_views
from rayvr.study import Config, Display, Motion, ReferenceSettings, StudySettings, measure
from rayvr.study.metrics import IMAGE_METRICS, METRICS
from rayvr.study.pool import MetricPool
from rayvr.study.progress import StudyProgress


def _images(seed, views=2, h=24, w=20):
    rng = np.random.default_rng(seed)
    ref = rng.gamma(2.0, 0.4, (views, h, w, 4)).astype(np.float32)
    test = (ref * rng.gamma(4.0, 0.25, ref.shape)).astype(np.float32)
    test[0, 0, 0, 1] = -0.01                          # a negative value: judged as shown (0), and counted
    return test, ref


def _judge_all(workers):
    display = Display().fixed(_images(0)[1])
    out = []
    with MetricPool(workers) as pool:
        pending = []
        for seed in range(3):
            test, ref = _images(seed)
            ecc = np.hypot(*np.meshgrid(np.arange(20) - 9.5, np.arange(24) - 11.5))[None].repeat(2, 0)   # degrees
            pending.append(pool.judge(test, ref, display, 14.0, 1e-2, (f"image {seed}", "reference"),
                                      tuple(METRICS), maps=seed == 0, units=1.0, eccentricity=ecc))
        out = [p.get() for p in pending]
    return out


def test_parallel_metrics_are_identical_to_serial():
    serial, parallel = _judge_all(0), _judge_all(2)
    for (sv, sm, sn), (pv, pm, pn) in zip(serial, parallel):
        assert sn == pn == 1
        assert set(sv) == set(pv) == set(METRICS)
        for m in METRICS:
            assert np.array_equal(sv[m], pv[m]), m
        assert set(sm) == set(pm)
        for m in sm:
            assert np.array_equal(sm[m], pm[m]), m
    assert set(serial[0][1]) == {"flip", "relmse"} and not serial[1][1]


def test_progress_counts_concurrent_work_by_worker_seconds_over_workers():
    p = StudyProgress(False)
    p.plan("render", 100.0)
    p.plan("metric", 100.0)
    with p.step("render", 50.0):
        pass
    p.done_s["render"] = 5.0                        # 0.1 s per render unit
    p.concurrent("metric", 4)
    p.finished("metric", 50.0, 20.0)                # 0.4 worker-seconds per unit
    assert p.rate("metric") == pytest.approx(0.4)
    # 50 render units here (5 s) beside 50 metric units on 4 workers (5 s): overlapped, not added
    assert p.remaining_s() == pytest.approx(5.0)
    p.finished("metric", 0.0, 3.0)                 # unplanned work teaches no rate
    assert p.rate("metric") == pytest.approx(0.4)
    p.concurrent("metric", 0)
    assert p.remaining_s() == pytest.approx(5.0 + 20.0)


def test_untimed_rendering_is_estimated_as_a_gpu_renders_it_beside_the_judging():
    from rayvr.study.progress import HARDWARE_RENDER_SCALE

    left = {}
    for hardware in (False, True):
        p = StudyProgress(False, hardware=hardware)
        p.plan("render", 1e9)
        p.plan("metric", 2e7)
        p.finished("metric", 1e7, 10.0)            # the first thing timed: a judgement, 1e-6 s a unit
        left[hardware] = p.remaining_s()
    # llvmpipe renders a unit at the metrics' pace: 1e9 x 1e-6 s; a GPU about 500x faster
    assert left[False] == pytest.approx(1e9 * 1e-6 + 1e7 * 1e-6)
    assert left[True] == pytest.approx(1e9 * 1e-6 * HARDWARE_RENDER_SCALE + 1e7 * 1e-6)


def test_metric_workers_yield_to_the_process_that_drives_the_gpu():
    from rayvr.study.pool import WORKER_NICENESS

    with MetricPool(1) as pool:
        niceness = pool.executor.submit(os.nice, 0).result(timeout=120)
    assert niceness == min(os.nice(0) + WORKER_NICENESS, 19)


def test_study_rows_are_identical_with_the_metric_pool(gpu):
    size, ref_settings = (12, 12), ReferenceSettings(frames=8, spp=2, max_bounces=3)
    scene = rv.scenes.cornell_box()
    ref = rv.tune.cached_reference(scene, default_views(scene, 1, size), ref_settings, False, gpu)
    results = []
    for workers in (0, 2):
        settings = StudySettings(frames=2, timing_frames=1, warmup=0, warmup_s=0.0,
                                 motion=Motion(frames=2, samples=1), floor_fraction=0.25, progressive_frames=2,
                                 metric_workers=workers)
        configs = [Config("all SHADOWS", Effect.SHADOWS, options={"path_bounces": 3}),
                   Config("PATH_TRACED 1 spp", Effect.PATH_TRACED, options={"spp": 1, "path_bounces": 3})]
        results.append(measure(scene, configs, views=1, size=size, reference=ref, settings=settings, cache_dir=False,
                               progress=False, gpu=gpu))
    serial, parallel = results
    assert serial.study["metric_workers"] == 0 and parallel.study["metric_workers"] == 2
    for a, b in zip(serial.rows, parallel.rows):
        assert a.errors == b.errors and a.motion == b.motion
        untimed = [{k: v for k, v in f.items() if k != "seconds"} for f in (a.floor, b.floor)]
        assert untimed[0] == untimed[1]
        for m in a.maps:
            assert np.array_equal(a.maps[m], b.maps[m])
    for a, b in zip(serial.curves, parallel.curves):
        timed = ("wall_s", "gpu_s")
        assert [{k: v for k, v in p.items() if k not in timed} for p in a.points] == \
               [{k: v for k, v in p.items() if k not in timed} for p in b.points]


def test_hdrflip_frames_limits_hdr_flip_to_the_first_judged_frames(gpu):
    size = (12, 12)
    scene = rv.scenes.cornell_box()
    ref = rv.tune.cached_reference(scene, default_views(scene, 1, size), ReferenceSettings(frames=4, spp=1,
                                                                                           max_bounces=2), False, gpu)
    settings = StudySettings(frames=3, timing_frames=1, warmup=0, warmup_s=0.0, motion=Motion(frames=2, samples=1),
                             floor_fraction=0.5, progressive_frames=2, hdrflip_frames=1)
    res = measure(scene, [Config("all SHADOWS", Effect.SHADOWS, options={"path_bounces": 2})], views=1, size=size,
                  reference=ref, settings=settings, cache_dir=False, progress=False, gpu=gpu)
    row = res.rows[0]
    assert row.errors["hdrflip"]["n"] == 1 and row.errors["flip"]["n"] == 3
    assert "hdrflip" not in row.motion and "flip" in row.motion
    assert "hdrflip" not in row.floor and "flip" in row.floor
    assert all("hdrflip" not in p and "flip" in p for c in res.curves for p in c.points)
    assert res.study["settings"]["hdrflip_frames"] == 1


def test_an_interrupted_study_stops_its_workers_at_once():
    import time

    test, ref = _images(0, views=2, h=600, w=600)
    display = Display().fixed(ref)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        with MetricPool(2) as pool:
            pool.judge(test, ref, display, 14.0, 1e-2, ("image", "reference"), IMAGE_METRICS, units=1.0)
            processes = list(pool.executor._processes.values())
            raise KeyboardInterrupt
    assert time.perf_counter() - t0 < 20
    assert processes and all(not p.is_alive() for p in processes)


def test_the_tuners_probe_gives_the_same_error_model_with_the_metric_pool(gpu):
    from rayvr.tune.cost_probe import ErrorJudge, probe_cost_model

    size = (12, 12)
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 1, size)
    ref = rv.tune.cached_reference(scene, views, ReferenceSettings(frames=4, spp=1, max_bounces=2), False, gpu)
    models = []
    for workers in (0, 2):
        with MetricPool(workers) as pool:
            judge = ErrorJudge(ref, Display().fixed(ref.image), 14.0, "flip", 1e-2, pool=pool if workers else None)
            models.append(probe_cost_model(scene, views, rv.tune.hybrid_graph, {"path_bounces": 2}, judge,
                                           levels=[Effect.RASTER, Effect.SHADOWS], frames=1, warmup=1, warmup_s=0.0,
                                           trials=2, progress=False, gpu=gpu)[0])
    serial, parallel = models
    assert serial.error == parallel.error and serial.rest_error == parallel.rest_error
    assert serial.error["BackWall"][Effect.SHADOWS] > 0


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="reads process states from /proc")
def test_quiet_stops_the_workers_while_the_gpu_is_timed_and_continues_them():
    def state(pid, want=None):
        """The process's state letter (waiting up to 2 s for `want`: a signal lands asynchronously)."""
        import time

        until = time.monotonic() + 2.0
        while True:
            with open(f"/proc/{pid}/stat") as f:
                s = f.read().rsplit(")", 1)[1].split()[0]
            if want is None or (s == "T") == (want == "T") or time.monotonic() > until:
                return s
            time.sleep(0.01)

    with MetricPool(2) as pool:
        pool.executor.submit(os.getpid).result(timeout=120)    # the workers are up
        pids = [p.pid for p in pool.executor._processes.values()]
        assert len(pids) == 2
        with pool.quiet():
            assert [state(pid, "T") for pid in pids] == ["T", "T"]
        assert all(state(pid, "running") != "T" for pid in pids)
        assert pool.executor.submit(os.getpid).result(timeout=60) in pids   # and they still work
    with MetricPool(0).quiet():      # no workers: nothing to stop
        pass
