"""What the trace decision's benchmarks share (view_reuse, foveation): one configuration timed,
its rays per view counted and its displayed image judged against a converged path-traced
reference by FLIP, FLIP within the foveal radius and FLIP weighted by eccentricity."""
from __future__ import annotations

import contextlib

import numpy as np

from ._dispatches import dispatch_ms, labelled_programs
from ._timing import wall_ms_per_frame


def add_common_arguments(parser, default_scene: str = "cornell_box") -> None:
    parser.add_argument("--scene", default=default_scene,
                        help="glTF path or built-in scene name; e.g. ../shared/scenes/tauray/test.glb")
    parser.add_argument("--preset", default="clean", help="the hybrid's preset: clean (default) or raw")
    parser.add_argument("--frames", type=int, default=30, help="timed frames per configuration (quick: 3)")
    parser.add_argument("--warmup", type=int, default=5, help="untimed frames first (quick: 1)")
    parser.add_argument("--judged-frames", type=int, default=16,
                        help="still frames rendered before the judged one (the denoiser's history; quick: 2)")
    parser.add_argument("--reference-frames", type=int, default=64,
                        help="frames of the path-traced reference (quick: 4)")
    parser.add_argument("--reference-spp", type=int, default=16, help="its paths per pixel per frame (quick: 4)")
    parser.add_argument("--dispatches", type=int, default=0,
                        help="frames over which to time each compute dispatch apart (a column of Pass/shader ms; "
                             "default 0: off)")
    parser.add_argument("--ppd", type=float, default=None,
                        help="FLIP's pixels per degree (default: the index headset's)")


def settings(args) -> dict:
    """The frame counts of a full run or --quick."""
    if args.quick:
        return {"frames": 3, "warmup": 1, "judged": 2, "ref_frames": 4, "ref_spp": 4,
                "dispatches": min(args.dispatches, 2)}
    return {"frames": args.frames, "warmup": args.warmup, "judged": args.judged_frames,
            "ref_frames": args.reference_frames, "ref_spp": args.reference_spp, "dispatches": args.dispatches}


def reference(scene, view_set, s: dict):
    """The converged path-traced image of `view_set` (linear, (views, h, w, c), row 0 at the top)."""
    from rayvr.study.reference import ReferenceSettings, cached_reference

    r = ReferenceSettings(frames=max(2, s["ref_frames"]), spp=s["ref_spp"])
    return cached_reference(scene, view_set, r, cache_dir=False).image


def measure(scene, view_set, graph, s: dict, judge_ref, ppd: float | None) -> dict:
    """Time `graph` on `view_set` (wall and GPU ms per frame), count its rays per view in the last
    frame, render still frames and judge the last one against `judge_ref`; with `s["dispatches"]`
    frames, also GPU ms per compute dispatch (benchmarks._dispatches)."""
    import rayvr as rv
    from rayvr.graphs import hdr_output
    from rayvr.study.display import Display
    from rayvr.study.metrics import evaluate
    from rayvr.xr import foveation
    from rayvr.xr.presets import get_preset

    with contextlib.ExitStack() as stack:
        rec = stack.enter_context(labelled_programs()) if s.get("dispatches") else None
        r = stack.enter_context(rv.Renderer(scene, graph, views=view_set))
        wall = wall_ms_per_frame(r, s["frames"], s["warmup"])
        profile = r.profile()
        gpu = profile.total_ms if r.gpu.caps.timer_queries else None
        passes = {name: round(st.mean_ms, 3) for name, st in profile.passes.items()} if gpu is not None else {}
        rays = r.compiled.ray_counts()
        dispatches = dispatch_ms(r, rec, s["dispatches"]) if rec is not None else {}
        for _ in range(s["judged"]):
            r.render()
        image = r.read_output(hdr_output(graph), flip_y=True)[..., :3].astype(np.float32)
    ecc = foveation.eccentricity_map(view_set, foveation.centre_tangents(view_set))[:, ::-1]
    display = Display().fixed(judge_ref[..., :3])
    per_view, _ = evaluate(image, judge_ref[..., :3], display, ppd or get_preset("index").pixels_per_degree,
                           which=("flip", "flip_fovea", "flip_ecc"), eccentricity=ecc)
    return {"wall_ms": wall, "gpu_ms": gpu, "rays": rays, "passes": passes, "dispatches": dispatches,
            **{m: float(np.mean(v)) for m, v in per_view.items()}}


class Progress:
    """A decision benchmark's progress bar over its references and configurations, with an ETA from
    the steps done (rayvr.study.progress). Each configuration's figures are written above the bar
    as it is measured, so a run a timeout cuts short keeps them in its log. `jobs`: (view set,
    configurations judged against its reference) for each reference the run renders."""

    def __init__(self, s: dict, jobs, desc: str):
        from rayvr.study.progress import StudyProgress

        self.s = s
        self.bar = StudyProgress(desc=desc)
        for view_set, configurations in jobs:
            self.bar.plan("render", self._units(view_set, True) + configurations * self._units(view_set, False))

    def _units(self, view_set, reference_: bool) -> float:
        """Pixel-frames rendered: the reference's paths, or a configuration's frames."""
        pixels = sum(v.width * v.height for v in view_set.views)
        frames = (max(2, self.s["ref_frames"]) * self.s["ref_spp"] if reference_
                  else self.s["warmup"] + self.s["frames"] + self.s["judged"] + self.s["dispatches"])
        return float(pixels * frames)

    def __enter__(self):
        self.bar.start()
        return self

    def __exit__(self, *exc):
        self.bar.close()

    def reference(self, scene, view_set):
        with self.bar.step("render", self._units(view_set, True), f"{len(view_set.views)} views: reference"):
            return reference(scene, view_set, self.s)

    def measure(self, label: str, scene, view_set, graph, judge_ref, ppd: float | None) -> dict:
        with self.bar.step("render", self._units(view_set, False), label):
            row = measure(scene, view_set, graph, self.s, judge_ref, ppd)
        self.bar.note(f"{label}: {ms(row):.3f} ms a frame, FLIP {row['flip']:.4f}, rays {sum(row['rays']):,}")
        return row


def ms(row: dict) -> float:
    """The GPU ms where the driver times it, else the wall ms."""
    return row["gpu_ms"] if row["gpu_ms"] is not None else row["wall_ms"]


def passes_cell(row: dict) -> str:
    """GPU ms per pass (timer queries' means), as "Name ms" pairs; empty without timer queries."""
    return " ".join(f"{name} {t:.3f}" for name, t in row["passes"].items())


def cells(row: dict) -> list:
    """wall ms, GPU ms, rays in all, FLIP, FLIP fovea, FLIP ecc-weighted."""
    return [round(row["wall_ms"], 3), "" if row["gpu_ms"] is None else round(row["gpu_ms"], 3), sum(row["rays"]),
            round(row["flip"], 4), round(row["flip_fovea"], 4), round(row["flip_ecc"], 4)]
