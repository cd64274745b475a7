"""rayvr.cluster: what splitting work over Ray workers costs and gains.

Measurements (`--measure`, comma-separated):
- `overhead`: one worker against two workers sharing the one GPU (half a GPU each), for a
  reference split by samples and a light-field frame split by views; with one GPU the speed-up
  can only be <= 1, and how far below 1 it is is the cluster's overhead.
- `reference`: the error study's reference (issue 18: tauray/test.glb, 2 x 1440x1600, 4096 spp,
  its two halves and the bounce check's 25% more frames) over --workers N workers: wall time,
  speed-up and parallel efficiency against 1 worker.
- `sequence`: a 48-view light-field sequence of 120 frames (512x683 per view, hybrid graph)
  split by frames: frames per second.
- `host-split`: one frame of 64 views of 512x683 over this host's GPUs (HostFrameSplitter):
  latency (frame start to the primary's array complete, copies included) and time per frame,
  against one worker and against one process rendering every view itself.
- `error-study`: the error-against-time study (rayvr.tune standard configurations, static
  frames only: motion, floors and curves off) split over the workers: wall time, and how far the
  table moves (errors, GPU ms) from the 1-worker table.

Every row's wall time is a warm run: each Cluster first runs a small job of the same kind so
that every worker has loaded the scene and compiled its graph; `startup s` is the Cluster's
start (workers up, contexts made). `--quick`: tiny sizes for llvmpipe, workers 1 and 2.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

DEFAULT_SCENE = str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb")
MEASUREMENTS = ("overhead", "reference", "sequence", "host-split", "error-study")
COLUMNS = ["measurement", "workers", "GPU/worker", "work", "startup s", "wall s", "speed-up", "efficiency",
           "rate", "note"]


def add_arguments(parser) -> None:
    parser.add_argument("--measure", default="overhead",
                        help=f"comma-separated: {', '.join(MEASUREMENTS)} (quick: all)")
    parser.add_argument("--scene", default=DEFAULT_SCENE, help="glTF path or built-in name (quick: cornell_box)")
    parser.add_argument("--workers", default="auto",
                        help="comma-separated worker counts, e.g. 1,2,4,8 (auto: 1 and powers of 2 up to the GPUs)")
    parser.add_argument("--address", help="an existing Ray cluster (default: a local one)")
    parser.add_argument("--spp", type=int, default=4096, help="reference samples per pixel (quick: 16)")
    parser.add_argument("--spp-per-frame", type=int, default=4, help="reference paths per pixel per frame")
    parser.add_argument("--ref-size", default="1440x1600", help="reference per-view size, 2 views (quick: 32x32)")
    parser.add_argument("--seq-views", type=int, default=48, help="light-field views of the sequence (quick: 4)")
    parser.add_argument("--seq-frames", type=int, default=120, help="sequence frames (quick: 8)")
    parser.add_argument("--lf-size", default="512x683", help="light-field per-view size (quick: 64x85)")
    parser.add_argument("--split-views", type=int, default=64, help="views of the split frame (quick: 4)")
    parser.add_argument("--split-frames", type=int, default=20, help="timed split frames (quick: 4)")
    parser.add_argument("--study-size", default="1440x1600", help="error study per-view size, 2 views (quick: 24x24)")


def _counts(text: str, ray) -> list[int]:
    if text != "auto":
        return [int(s) for s in text.split(",") if s.strip()]
    gpus = int(ray.cluster_resources().get("GPU", 0))
    counts = [1] + [n for n in (2, 4, 8, 16) if n <= max(gpus, 2)]
    return counts if gpus else [1, 2]


def _row(measurement, workers, gpu_share, work, startup, wall, base, rate, note=""):
    speedup = base / wall if base else 1.0
    return [measurement, workers, round(gpu_share, 3), work, round(startup, 2), round(wall, 3), round(speedup, 3),
            round(speedup / workers, 3), rate, note]


def run(args) -> dict:
    import ray

    import rayvr as rv
    import rayvr.cluster as rc
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.xr.cameras import default_views

    quick = args.quick
    measures = list(MEASUREMENTS) if quick and args.measure == "overhead" else \
        [m.strip() for m in args.measure.split(",") if m.strip()]
    for m in measures:
        if m not in MEASUREMENTS:
            raise rv.OptionError(f"--measure {m}: use some of {', '.join(MEASUREMENTS)}")
    spec = "cornell_box" if quick and args.scene == DEFAULT_SCENE else args.scene
    scene = load_scene_arg(spec)
    payload = rc.ScenePayload.of(spec)
    ref_size = (32, 32) if quick and args.ref_size == "1440x1600" else parse_size(args.ref_size)
    lf_size = (64, 85) if quick and args.lf_size == "512x683" else parse_size(args.lf_size)
    study_size = (24, 24) if quick and args.study_size == "1440x1600" else parse_size(args.study_size)
    spp = 16 if quick and args.spp == 4096 else args.spp
    spf = 1 if quick else args.spp_per_frame
    seq_views = 4 if quick and args.seq_views == 48 else args.seq_views
    seq_frames = 8 if quick and args.seq_frames == 120 else args.seq_frames
    split_views = 4 if quick and args.split_views == 64 else args.split_views
    split_frames = 4 if quick and args.split_frames == 20 else args.split_frames

    started = not ray.is_initialized()
    if started:
        ray.init(address=args.address, include_dashboard=False, log_to_driver=False, logging_level="error")
    gpus = float(ray.cluster_resources().get("GPU", 0))
    counts = [1, 2] if quick and args.workers == "auto" else _counts(args.workers, ray)
    rows, notes = [], []
    ref_views = default_views(scene, 2, ref_size)
    lf_views = default_views(scene, seq_views, lf_size)

    def reference_job(c, frames):
        return rc.converge_reference(scene, ref_views, frames=frames, spp=spf, cluster=c, payload=payload,
                                     progress=False)

    def reference_frames(frames):
        """Frames a reference of `frames` renders: its own and the bounce check's."""
        return frames + rv.tune.ReferenceSettings(frames, spf).bounce_check_frames

    def views_job(c):
        return rc.render_views(scene, rv.graphs.hybrid(preset="raw"), lf_views, cluster=c, payload=payload, progress=False)

    def timed(fn):
        t0 = time.perf_counter()
        fn()
        return time.perf_counter() - t0

    def with_cluster(n, share, body, same_node=False):
        t0 = time.perf_counter()
        with rc.Cluster(n, gpus_per_worker=share, same_node=same_node) as c:
            return body(c, time.perf_counter() - t0)

    ref_frames = max(2, spp // spf // 2 * 2)      # two equal halves
    try:
        if "overhead" in measures:
            one_gpu = 1.0 if gpus >= 1 else 0.0
            base = {}
            for n in (1, 2):
                share = one_gpu / n

                def body(c, startup, n=n, share=share):
                    reference_job(c, 2 * n)                      # warm: scene loaded, graph compiled
                    views_job(c)
                    t_ref = timed(lambda: reference_job(c, ref_frames))
                    t_views = timed(lambda: views_job(c))
                    return startup, t_ref, t_views

                startup, t_ref, t_views = with_cluster(n, share, body)
                base.setdefault("ref", t_ref)
                base.setdefault("views", t_views)
                rows.append(_row("overhead: reference", n, share, f"2x{ref_size[0]}x{ref_size[1]} {spp} spp",
                                 startup, t_ref, base["ref"], f"{reference_frames(ref_frames) / t_ref:.3g} frames/s",
                                 "one GPU shared"))
                rows.append(_row("overhead: views", n, share, f"{seq_views}x{lf_size[0]}x{lf_size[1]}", startup,
                                 t_views, base["views"], f"{1e3 * t_views:.4g} ms/frame", "one GPU shared"))
            notes.append("overhead rows: every worker count shares one GPU (or the CPU), so speed-up 1.0 = no "
                         "overhead; efficiency is not meaningful there")
        if "reference" in measures:
            base = None
            for n in counts:
                def body(c, startup):
                    reference_job(c, 2 * c.size)
                    return startup, timed(lambda: reference_job(c, ref_frames))

                startup, wall = with_cluster(n, None, body)
                base = base or wall
                samples = 2 * ref_size[0] * ref_size[1] * spf * reference_frames(ref_frames)
                rows.append(_row("reference", n, 1.0 if gpus >= n else gpus / n,
                                 f"2x{ref_size[0]}x{ref_size[1]} {spp} spp", startup, wall, base,
                                 f"{samples / wall / 1e6:.4g} Msamples/s", "bounce check included"))
        if "sequence" in measures:
            seq = rc.TrajectoryViews(lf_views, "turn", frames=seq_frames)
            base = None
            for n in counts:
                def body(c, startup):
                    rc.render_sequence(scene, rv.graphs.hybrid(preset="raw"), rc.TrajectoryViews(lf_views, "turn", frames=c.size),
                                       pins=(), chunk=1, cluster=c, payload=payload, progress=False)
                    result = rc.render_sequence(scene, rv.graphs.hybrid(preset="raw"), seq, pins=(), cluster=c, payload=payload,
                                                progress=False)
                    return startup, result.seconds

                startup, wall = with_cluster(n, None, body)
                base = base or wall
                rows.append(_row("sequence", n, 1.0 if gpus >= n else gpus / n,
                                 f"{seq_frames} frames x {seq_views}x{lf_size[0]}x{lf_size[1]}", startup, wall, base,
                                 f"{seq_frames / wall:.4g} frames/s", "pixels not returned"))
        if "host-split" in measures:
            split_set = default_views(scene, split_views, lf_size)
            one_ms = _one_process_ms(scene, split_set, split_frames)
            rows.append(_row("host-split: one process", 1, 1.0 if gpus else 0.0,
                             f"{split_views}x{lf_size[0]}x{lf_size[1]}", 0.0, one_ms / 1e3, one_ms / 1e3,
                             f"{one_ms:.4g} ms/frame", "the driver renders every view, no copies"))
            for n in counts:
                def body(c, startup):
                    with rc.HostFrameSplitter(scene, rv.graphs.hybrid(preset="raw"), split_set, cluster=c, payload=payload) as s:
                        for _ in range(4 + 2 * c.size):       # compile, then let the shares settle
                            s.render()
                        t0 = time.perf_counter()
                        timings = [s.render() for _ in range(split_frames)]
                        per_frame = (time.perf_counter() - t0) / split_frames
                    return startup, per_frame, timings

                startup, per_frame, timings = with_cluster(n, None, body, same_node=True)
                latency = sum(t.latency_ms for t in timings) / len(timings)
                render = sum(max(t.render_ms) for t in timings) / len(timings)
                rows.append(_row("host-split", n, 1.0 if gpus >= n else gpus / n,
                                 f"{split_views}x{lf_size[0]}x{lf_size[1]}", startup, per_frame, one_ms / 1e3,
                                 f"{latency:.4g} ms latency",
                                 f"slowest share renders {render:.4g} ms; shares {timings[-1].shares}; "
                                 f"copy {timings[-1].copy_ms:.3g} ms"))
            notes.append("host-split speed-up is against one process rendering every view (no Ray, no copies)")
        if "error-study" in measures:
            study_views = default_views(scene, 2, study_size)
            ref_settings = rv.tune.ReferenceSettings(8 if quick else 256, 1 if quick else 4)
            configs = rv.tune.standard_configs(scene, ref_settings, spp=(1, 4) if quick else (1, 4, 16))
            frames, timing, warmup = (2, 2, 1) if quick else (4, 50, 10)
            settings = rv.tune.StudySettings(frames=frames, timing_frames=timing, warmup=warmup,
                                             warmup_s=0.0 if quick else None, motion=None, floors=False,
                                             progressive_frames=0, metrics=("relmse", "psnr"))
            warm = dataclasses.replace(settings, frames=1, timing_frames=1, warmup=0, metrics=("relmse",))
            base, base_rows = None, None
            reference = None
            for n in counts:
                def body(c, startup):
                    nonlocal reference
                    study = {"reference": None, "views": study_views, "cache_dir": False, "curves": False,
                             "cluster": c, "payload": payload, "progress": False}
                    if reference is None:
                        reference = rc.converge_reference(scene, study_views, settings=ref_settings, cluster=c,
                                                          payload=payload, progress=False)
                    study["reference"] = reference
                    rc.measure(scene, configs[:c.size], settings=warm, **study)
                    t0 = time.perf_counter()
                    res = rc.measure(scene, configs, settings=settings, **study)
                    return startup, time.perf_counter() - t0, res

                startup, wall, res = with_cluster(n, None, body)
                base = base or wall
                base_rows = base_rows or res.rows
                d_err = max(abs(a.mean("relmse") - b.mean("relmse")) / max(abs(b.mean("relmse")), 1e-12)
                            for a, b in zip(res.rows, base_rows))
                d_ms = max(a.gpu_ms / b.gpu_ms for a, b in zip(res.rows, base_rows))
                rows.append(_row("error-study", n, 1.0 if gpus >= n else gpus / n,
                                 f"{len(configs)} configs 2x{study_size[0]}x{study_size[1]}", startup, wall, base,
                                 f"{len(configs) / wall:.3g} configs/s",
                                 f"relMSE moves {d_err:.2g} (relative), GPU ms up to {d_ms:.3g}x the 1-worker row"))
    finally:
        if started:
            ray.shutdown()
    notes.append(f"Ray cluster: {gpus:g} GPU(s); wall times are warm (scene loaded, graphs compiled)")
    return {"columns": COLUMNS, "rows": rows, "notes": notes}


def _one_process_ms(scene, views, frames: int) -> float:
    """Wall ms per frame of one process rendering all `views` with the hybrid graph: its array
    is complete on its own GPU, with no copies."""
    import rayvr as rv

    from ._timing import wall_ms_per_frame

    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=views) as r:
        return wall_ms_per_frame(r, frames, 2)
