"""The error study: every configuration's GPU time and image error against a trusted reference.

    results = rv.study.measure(scene, rv.tune.standard_configs(scene), views=2, size=(64, 64))
    print(results.table())
    rv.tune.write_report(results, "out/study")   # report.md, report.html, results.json, images

For each configuration (rayvr.study.configs.Config):
- **time**: GPU ms per frame from the graph's profile over `timing_frames` frames after a
  warm-up (rayvr.study.timing);
- **error, static view**: `frames` frames (each after the configuration's own accumulation), the
  first after `warmup + timing_frames` frames of history (a count: the judged frames and their
  seeds never depend on the GPU's speed; with a warm-up timed in seconds the timing follows
  them, else the timed frames are the history), every
  metric of rayvr.study.metrics.evaluate per frame and view against the reference; reported as the
  mean and standard deviation over those frames and views;
- **error in motion**: the views carried along a headset trajectory (rayvr.study.motion), the
  sampled frames judged against a reference rendered for each of them;
- **bias floor**: the configuration converged, against the reference (rayvr.study.floor).
Then the progressive-convergence curves (rayvr.study.progressive.progressive_curve).

The reference (rayvr.study.reference) is converged and checked; every render has its own seeds
(rayvr.study.seeds). The displayed images go through one fixed tone mapping
(rayvr.study.display); FLIP uses the headset preset's pixels per degree. The scene's material
effects are restored afterwards. A runner (rayvr.study.runner) says where the steps run: here, or
with rayvr.cluster's StudyRunner on Ray workers (each row then names the worker that timed it).
"""
from __future__ import annotations

import contextlib
import dataclasses
import math
import time

import numpy as np

from ..errors import OptionError
from ..materials.effect import Effect
from ..xr import foveation
from . import seeds
from .configs import Config, effects_restored, path_traced_graph
from .defaults import machine_defaults
from .display import Display
from .floor import bias_floor, even_frames, floor_path, load_floor, store_floor
from .metrics import DEFAULT_EPS, METRICS, check_metrics
from .motion import Motion, along, trajectory_views
from .pool import MetricPool, default_workers
from .progress import StudyProgress
from .reference import Reference, ReferenceProgress, ReferenceSettings, is_cached
from .results import Results, Row, summarize
from .row_cache import image_digest, load_row, row_key, row_path, store_row
from .runner import LocalRunner
from .timing import default_warmup_s, make_views, timed_frames

MOTION_FIRST_FRAME = seeds.TEST + seeds.RANGE // 2     # inside the test range, apart from the static frames
PROGRESSIVE_FIRST_FRAME = seeds.TEST + seeds.RANGE // 4
# Relative CPU cost per pixel of each metric, measured on the Cornell box (benchmarks/RESULTS.md,
# "Where the error study's time goes"; FLIP's includes the tone mapping, 2.5 us per pixel on one
# core; HDR-FLIP runs LDR-FLIP at each of the reference's exposures).
METRIC_COST = {"flip": 1.0, "hdrflip": 7.5, "ssim": 0.25, "psnr": 0.01, "relmse": 0.03, "relmse_trim": 0.01,
               "fireflies": 0.01, "flip_fovea": 0.01, "flip_ecc": 0.01}
# Relative GPU cost per pixel and frame of an effect level, in paths of the reference's length.
EFFECT_COST = {Effect.RASTER: 0.3, Effect.SHADOWS: 0.5, Effect.REFLECTIONS: 0.8}


@dataclasses.dataclass(frozen=True)
class StudySettings:
    """How much the study renders and how it judges (see the module docstring).

    `frames`: judged frames per configuration (static view); `timing_frames`/`warmup`: timed and
    untimed frames; `warmup_s`: seconds of untimed frames first (None: 0.5 s on a GPU with timer
    queries, 0 on llvmpipe); `motion`: the trajectory (None: static only); `floors`: render the
    bias floors, at `floor_fraction` of the reference's samples per pixel; `progressive_frames`:
    length of the progressive curves (0: none); `preset`/`ppd`: FLIP's pixels per degree (ppd
    None: the preset's); `eps`: relMSE's epsilon; `display`: the tone mapping of the displayed
    images; `metric_workers`: processes judging the images while the GPU renders on
    (rayvr.study.pool; 0: here, one after the other; None: pool.default_workers, os.cpu_count() - 2 from 256x256 pixels per
    view, else 0); the numbers are the same either way. `hdrflip_frames`: HDR-FLIP (the costliest
    metric: LDR-FLIP at each of the reference's exposures, ~8x its cost on the Cornell box) on the
    first N judged frames of each configuration only, not in motion, on the floors nor on the
    progressive curves (None: everywhere)."""

    frames: int = 4
    timing_frames: int = 20
    warmup: int = 3
    warmup_s: float | None = None
    motion: Motion | None = Motion()
    floors: bool = True
    floor_fraction: float = 0.25
    progressive_frames: int = 64
    preset: str = "index"
    ppd: float | None = None
    eps: float = DEFAULT_EPS
    display: Display = Display()
    metrics: tuple = tuple(METRICS)
    metric_workers: int | None = None
    hdrflip_frames: int | None = None

    def __post_init__(self):
        for key, low in (("frames", 1), ("timing_frames", 1), ("warmup", 0), ("progressive_frames", 0)):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise OptionError(f"study {key}: must be an integer >= {low}, got {value!r}")
        if self.metric_workers is not None and (isinstance(self.metric_workers, bool)
                                                or not isinstance(self.metric_workers, int) or self.metric_workers < 0):
            raise OptionError(f"study metric_workers: must be an integer >= 0 or None, got {self.metric_workers!r}")
        if self.hdrflip_frames is not None and (isinstance(self.hdrflip_frames, bool)
                                                or not isinstance(self.hdrflip_frames, int) or self.hdrflip_frames < 1):
            raise OptionError(f"study hdrflip_frames: must be an integer >= 1 or None, got {self.hdrflip_frames!r}")
        if self.ppd is not None and not self.ppd > 0:
            raise OptionError(f"study ppd: pixels per degree must be > 0, got {self.ppd!r}")
        if not 0 < self.floor_fraction <= 1:
            raise OptionError(f"study floor_fraction: must be in (0, 1], got {self.floor_fraction!r}")
        if not self.eps > 0:
            raise OptionError(f"study eps: must be > 0, got {self.eps!r}")
        check_metrics(self.metrics)

    def workers_for(self, view_set) -> int:
        """Processes that judge the images of `view_set` (metric_workers; None: by view size)."""
        if self.metric_workers is not None:
            return self.metric_workers
        return default_workers(view_set.size[0] * view_set.size[1])

    def pixels_per_degree(self) -> float:
        from ..xr.presets import get_preset

        return float(self.ppd) if self.ppd is not None else get_preset(self.preset).pixels_per_degree

    def as_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["motion"] = self.motion.as_dict() if self.motion else None
        d["display"] = self.display.as_dict()
        d["metrics"] = list(self.metrics)
        d.pop("metric_workers")         # where the metrics ran, not what they are (the report's study info says)
        return d


# A probe ray (its trace, shadow ray and share of the update's blending) in reference-length
# paths: the Cornell box's probe GI frames at 2x32x32 on llvmpipe took 13x a 1 spp path-traced one.
PROBE_RAY_COST = 0.5


def frame_cost(config: Config, scene, pixels: int | None = None) -> float:
    """Expected GPU cost per pixel of one frame of `config`, in reference-length paths; with
    `pixels` (the frame's, all views) probe GI's rays, a fixed cost per frame, are shared out."""
    settings = config.settings()
    levels = set(config.assignment(scene).values())
    cost = max((settings["spp"] + 0.3) if e == Effect.PATH_TRACED else EFFECT_COST[e] for e in levels)
    if pixels and settings["gi"] == "probes":
        from ..passes.probe_gi import ProbeGI

        probes = {**ProbeGI.PROPERTIES, **(config.options.get("probes") or {})}
        try:
            rays = math.prod(int(n) for n in probes["counts"]) * int(probes["rays_per_probe"])
        except (TypeError, ValueError):   # the pass says what is wrong with them when it compiles
            rays = 0
        cost += PROBE_RAY_COST * rays / pixels
    return cost


def floor_frames(config: Config, reference_settings: ReferenceSettings, fraction: float) -> int:
    """Frames of a configuration's converged render: `fraction` of the reference's paths per
    pixel, at the configuration's spp (even, at least 2)."""
    spp = max(1, config.settings()["spp"])
    return even_frames(math.ceil(reference_settings.samples_per_pixel * fraction / spp))


def check_configs(scene, configs) -> list[Config]:
    configs = list(configs)
    if not configs:
        raise OptionError("measure: no configurations; pass e.g. rv.tune.standard_configs(scene)")
    for c in configs:
        if not isinstance(c, Config):
            raise OptionError(f"measure: {c!r} is not a rayvr.study.Config")
        c.assignment(scene)          # an unknown material fails now, not after the reference
    names = [c.name for c in configs]
    if len(set(names)) != len(names):
        raise OptionError(f"measure: configuration names must be unique, got {names}")
    return configs


def measure(scene, configs, views=2, size=(64, 64), reference: ReferenceSettings | Reference | None = None,
            settings: StudySettings = StudySettings(), cache_dir=None, progress: bool = True, gpu=None,
            curves: bool = True, notes=(), runner=None) -> Results:
    """Run the error study (module docstring) and return its Results.

    `views`: a ViewSet, or a view count from the scene's camera at `size` per view.
    `reference`: ReferenceSettings to render (or load from `cache_dir`; False: no cache) the
    reference with (None: the machine's defaults, rendered until converged: rayvr.study.defaults),
    or a Reference already made for these views. `curves`: the progressive
    curves. `notes`: lines for the report (e.g. why these sizes were chosen). `runner`: where
    the steps run (default rayvr.study.runner.LocalRunner: here, on `gpu`)."""
    from ..gpu import get_context

    t0 = time.perf_counter()
    gpu = gpu or get_context()
    runner = runner or LocalRunner()
    configs = check_configs(scene, configs)
    view_set = make_views(scene, views, size)
    ppd = settings.pixels_per_degree()
    warmup_s = default_warmup_s(gpu) if settings.warmup_s is None else float(settings.warmup_s)
    given = reference if isinstance(reference, Reference) else None
    ref_settings = given.settings if given else (reference or machine_defaults(gpu).reference_settings())
    if given is not None and given.image.shape[:3] != (len(view_set), view_set.size[1], view_set.size[0]):
        raise OptionError(f"measure: the reference has {given.image.shape[0]} view(s) of {given.image.shape[2]}x"
                          f"{given.image.shape[1]}, the study renders {len(view_set)} of "
                          f"{view_set.size[0]}x{view_set.size[1]}")
    motion = settings.motion
    study = Study(scene, view_set, ref_settings, settings, ppd, warmup_s, cache_dir, gpu,
                  StudyProgress(progress and not runner.shows_progress, f"error study {scene.name}",
                                hardware=not gpu.caps.is_software), runner)
    study.plan(configs, given is None, curves)
    # rows and curves on a cluster judge their images there; only a local study needs the pool
    study.pool = MetricPool(study.metric_workers() if isinstance(runner, LocalRunner) else 0, study.progress)
    study.share_scene = True    # its configurations render from one upload of the scene
    with effects_restored(scene), study.progress, study.pool, contextlib.closing(study):
        ref = given or study.reference(0, view_set, "reference")
        study.display = settings.display.fixed(ref.image)
        # judged while the study renders on (HDR-FLIP of a stereo 1440x1600 pair: ~1 CPU-minute)
        halves_judged = study.judge_later(ref.half_a, ref.half_b, "reference half A")
        motion_refs = [(i, study.reference(k + 1, _views(study.motion_frames[i]),
                                           f"reference of trajectory frame {i}"))
                       for k, i in enumerate(motion.sample_frames())] if motion else []
        rows = runner.rows(study, configs, ref, dict(motion_refs))
        made = runner.curves(study, ref) if curves and settings.progressive_frames else []
        halves = halves_judged.get()[0]
    info = {"scene": scene.name, "views": len(view_set), "size": list(view_set.size), "preset": settings.preset,
            "ppd": ppd, "ppd_source": "given" if settings.ppd else f"preset '{settings.preset}' (resolution / fov)",
            "display": study.display.as_dict(), "display_text": study.display.describe(), "eps": settings.eps,
            "timing": study.method or "?", "warmup_s": warmup_s, "device": gpu.caps.renderer,
            "software": bool(gpu.caps.is_software), "workers": sorted({r.timed_on for r in rows if r.timed_on}),
            "metric_workers": study.pool.workers, "metric_worker_s": study.pool.worker_s,
            "settings": settings.as_dict(), "notes": list(notes),
            "reference_halves": {m: float(np.mean(v)) for m, v in halves.items()},
            "seconds": time.perf_counter() - t0, "metric_descriptions": {m: d for m, d in _descriptions().items()
                                                                      if m in settings.metrics}}
    return Results(ref, rows, made, info, motion_refs)


class _ReferenceSteps(ReferenceProgress):
    """A reference's extensions as steps of the study's progress bar (`units` per frame)."""

    def __init__(self, progress, units: float, label: str):
        self.progress, self.units, self.label = progress, units, label

    @contextlib.contextmanager
    def step(self, frames: int, label: str):
        with self.progress.step("render", self.units * frames, f"{self.label}: {label}") as tick:
            yield lambda done: tick(done / max(frames, 1))

    def forecast(self, frames: int) -> None:
        self.progress.plan("render", self.units * frames)


def _descriptions() -> dict:
    from .metrics import DESCRIPTIONS

    return DESCRIPTIONS


def _views(views: list):
    from ..xr.views import ViewSet

    return ViewSet(views)


class Study:
    """One run of `measure`: shared state, the progress plan, and the steps. A cluster worker
    makes its own from `spec()` (`Study.from_spec`) to run `row` and `curve` on its GPU; floors
    it renders without a cache are kept in `new_floors` for the driver's cache."""

    def __init__(self, scene, view_set, ref_settings, settings, ppd, warmup_s, cache_dir, gpu, progress,
                 runner=None, motion_frames=None):
        self.scene, self.view_set, self.ref_settings, self.s = scene, view_set, ref_settings, settings
        self.ppd, self.warmup_s, self.cache_dir, self.gpu, self.progress = ppd, warmup_s, cache_dir, gpu, progress
        self.runner = runner or LocalRunner()
        self.pixels = len(view_set) * view_set.size[0] * view_set.size[1]
        # degrees of each pixel from its view's centre, in the judged images' row order (top first):
        # the foveal metrics' (the trajectory moves the views, not their frusta)
        self.eccentricity = foveation.eccentricity_map(view_set, foveation.centre_tangents(view_set))[:, ::-1]
        if motion_frames is None:
            motion_frames = trajectory_views(view_set, settings.motion) if settings.motion else []
        self.motion_frames = motion_frames          # the views of every trajectory frame
        self.display = None
        self.method = None
        self.pool = MetricPool(0, progress)     # measure() gives it workers
        self.keep_floors = False        # keep floors rendered without a cache in new_floors
        self.new_floors: dict = {}      # configuration name -> Floor
        self._digests: dict = {}        # id(reference image) -> its image_digest
        self.share_scene = False        # the rows' Renderers share one GpuScene (loaded_scene)
        self._gpu_scene = None

    def loaded_scene(self):
        """The GpuScene the rows' Renderers share (loaded on first use), or None when each loads
        its own (share_scene False: a cluster worker's study)."""
        if not self.share_scene:
            return None
        if self._gpu_scene is None:
            from ..scene.gpu_scene import GpuScene

            self._gpu_scene = GpuScene(self.gpu, self.scene)
        return self._gpu_scene

    def close(self) -> None:
        """Release the shared GpuScene."""
        if self._gpu_scene is not None:
            self._gpu_scene.release()
            self._gpu_scene = None

    def spec(self) -> dict:
        """What a worker needs to run this study's rows and curves (after the display is fixed;
        the trajectory's views travel made, as a pose log may exist only on this machine)."""
        return {"view_set": self.view_set, "ref_settings": self.ref_settings, "settings": self.s, "ppd": self.ppd,
                "display": self.display, "motion_frames": self.motion_frames}

    @classmethod
    def from_spec(cls, scene, spec: dict, gpu) -> "Study":
        """A study of `spec` on `gpu` (its own warm-up default, no cache, no progress bar)."""
        s = spec["settings"]
        warmup_s = default_warmup_s(gpu) if s.warmup_s is None else float(s.warmup_s)
        study = cls(scene, spec["view_set"], spec["ref_settings"], s, spec["ppd"], warmup_s, False, gpu,
                    StudyProgress(False), motion_frames=spec["motion_frames"])
        study.display = spec["display"]
        study.keep_floors = True
        return study

    def metric_workers(self) -> int:
        """Processes that judge the images (StudySettings.workers_for)."""
        return self.s.workers_for(self.view_set)

    # -- planning ----------------------------------------------------------------------------
    def _reference_units(self) -> float:
        r = self.ref_settings
        return self.pixels * r.spp * (r.frames + r.bounce_check_frames)

    def plan(self, configs, render_reference: bool, curves: bool) -> None:
        p, s = self.progress, self.s
        if render_reference and not is_cached(self.scene, self.view_set, self.ref_settings, self.cache_dir):
            p.plan("render", self._reference_units())
        p.plan("metric", self._units(True))          # the reference's halves
        if s.motion:
            for k, i in enumerate(s.motion.sample_frames()):
                if not is_cached(self.scene, _views(self.motion_frames[i]), self.ref_settings, self.cache_dir, k + 1):
                    p.plan("render", self._reference_units())
        for c in configs:
            for kind, units in self._row_units(c).items():
                p.plan(kind, units)
        if curves and s.progressive_frames:
            from .progressive import snapshot_counts

            for _ in self.curve_graphs():
                p.plan("setup", 1)
                p.plan("render", self._curve_cost() * (s.warmup + s.timing_frames + s.progressive_frames))
                p.plan("metric", self._units(s.hdrflip_frames is None) * len(snapshot_counts(s.progressive_frames)))

    def _row_units(self, c) -> dict:
        """The progress units (by kind) that measuring configuration `c` plans."""
        s = self.s
        cost = frame_cost(c, self.scene, self.pixels) * self.pixels
        timed = self.history_frames if self.warmup_s else 0   # the history, then the timing apart
        units = {"setup": 1.0, "render": cost * (self.history_frames + timed + s.frames * c.accumulate),
                 "metric": sum(self._units(self._hdrflip(k)) for k in range(s.frames))}
        if s.motion:
            units["setup"] += 1
            units["render"] += cost * s.motion.frames
            units["metric"] += self._units(s.hdrflip_frames is None) * s.motion.samples
        if s.floors:
            if not self._floor_cached(c):
                units["render"] += cost * floor_frames(c, self.ref_settings, s.floor_fraction)
            units["metric"] += self._units(s.hdrflip_frames is None)
        return units

    def _row_path(self, config, ref: Reference, motion_refs: dict):
        """Where `config`'s finished row is cached (rayvr.study.row_cache), or None without a cache."""
        if self.cache_dir is False:
            return None
        digests = [self._digest(ref)] + [f"{i}:{self._digest(r)}" for i, r in sorted(motion_refs.items())]
        return row_path(self.scene, row_key(self.scene, self.view_set, config, self.s.as_dict(), digests),
                        self.cache_dir)

    def _digest(self, ref: Reference) -> str:
        key = id(ref.image)
        if key not in self._digests:
            self._digests[key] = image_digest(ref.image)
        return self._digests[key]

    @property
    def history_frames(self) -> int:
        """Frames every configuration renders before its first judged one: a count, never a time."""
        return self.s.warmup + self.s.timing_frames

    def _hdrflip(self, k: int) -> bool:
        """Whether the k-th judged frame of a configuration gets HDR-FLIP (StudySettings.hdrflip_frames)."""
        return self.s.hdrflip_frames is None or k < self.s.hdrflip_frames

    def _curve_cost(self) -> float:
        """GPU cost per frame of a progressive curve (1 spp path tracing), as frame_cost counts it."""
        return (1 + 0.3) * self.pixels

    def _floor_frames(self, config) -> int:
        return floor_frames(config, self.ref_settings, self.s.floor_fraction)

    def _floor_cached(self, config) -> bool:
        if self.cache_dir is False:
            return False
        return floor_path(self.scene, config, self.view_set, self._floor_frames(config), self.cache_dir).exists()

    def cached_floor(self, config):
        """`config`'s floor from the cache, or None (not there, or no cache)."""
        if self.cache_dir is False:
            return None
        return load_floor(self.scene, config, self.view_set, self._floor_frames(config), self.cache_dir)

    def store_floor(self, config, floor) -> None:
        """Put a floor rendered elsewhere (a worker) into this study's cache."""
        if self.cache_dir is not False:
            store_floor(self.scene, config, self.view_set, floor, self.cache_dir)

    # -- steps -------------------------------------------------------------------------------
    def reference(self, sample: int, view_set, label: str) -> Reference:
        """The reference of `view_set` (trajectory sample `sample`; 0: the static view), its first
        round and extensions as steps of the progress bar."""
        r = self.ref_settings
        return self.runner.reference(self.scene, view_set, r, self.cache_dir, sample, self.s.eps, self.gpu,
                                     progress=_ReferenceSteps(self.progress, self.pixels * r.spp, label))

    def judge(self, image, reference_image, name: str, maps: bool = False):
        """(per-view metrics, maps, negative values) of `image`: negative radiance is judged as
        the tone mapper shows it (0), and counted."""
        return self.judge_later(image, reference_image, name, maps).get()

    def judge_later(self, image, reference_image, name: str, maps: bool = False, hdrflip: bool = True):
        """`judge` handed to the metric pool (rayvr.study.pool): a Pending whose get() is judge's
        answer; the study renders on meanwhile. `hdrflip` False: without HDR-FLIP (where
        StudySettings.hdrflip_frames leaves it out)."""
        return self.pool.judge(image, reference_image, self.display, self.ppd, self.s.eps, (name, "reference"),
                               self._which(hdrflip), maps, units=self._units(hdrflip), eccentricity=self.eccentricity)

    def judge_curve(self, image, reference_image, name: str):
        """judge_later for a progressive curve's snapshot (no HDR-FLIP when hdrflip_frames is set)."""
        return self.judge_later(image, reference_image, name, hdrflip=self.s.hdrflip_frames is None)

    def _which(self, hdrflip: bool) -> tuple:
        """The metrics of one judged image with or without HDR-FLIP (all of them where HDR-FLIP is
        the only one)."""
        return tuple(m for m in self.s.metrics if hdrflip or m != "hdrflip") or tuple(self.s.metrics)

    def _units(self, hdrflip: bool) -> float:
        """Metric units of one judged image with or without HDR-FLIP."""
        return self.pixels * sum(METRIC_COST[m] for m in self._which(hdrflip))

    def row(self, config: Config, ref: Reference, motion_refs: dict, floor=None) -> Row:
        """`config` measured: timing, the judged frames, in motion, its bias floor (`floor`: one
        already loaded, else from the cache or rendered)."""
        return self.row_later(config, ref, motion_refs, floor)()

    def row_later(self, config: Config, ref: Reference, motion_refs: dict, floor=None):
        """`row` with its images rendered and handed to the metric pool: returns the function
        that waits for their judgements and makes the Row (LocalRunner renders the next
        configuration before calling it)."""
        from ..renderer import Renderer

        s, p = self.s, self.progress
        path = self._row_path(config, ref, motion_refs)
        stored = load_row(path) if path is not None else None
        if stored is not None:      # measured by an earlier run of the same study
            for kind, units in self._row_units(config).items():
                p.plan(kind, -units)
            stored.name = config.name

            def cached() -> Row:
                return stored
            cached.ready = lambda: True
            return cached
        cost = frame_cost(config, self.scene, self.pixels) * self.pixels
        config.apply(self.scene)
        graph = config.build_graph()
        pin = config.output_pin(graph)
        name = f"config '{config.name}' {pin}"
        judged, first = [], None
        with p.step("setup", 1, config.name):
            r = Renderer(self.scene, graph, views=self.view_set, gpu=self.gpu, first_frame=seeds.TEST,
                         gpu_scene=self.loaded_scene())
        with r:
            accumulators = [n for n, q in r.compiled.passes.items() if type(q).__name__ == "Accumulate"]
            # The judged frames come after a counted history of warmup + timing_frames frames. A
            # warm-up timed in seconds renders as many frames as the GPU manages, so after it a
            # temporal method's history and the frames' seeds would depend on the GPU's speed and
            # load (two workers sharing a GPU judged other frames): there the history is rendered
            # first and the timing follows the judged frames; without one the timed frames are it.
            timed_first = not self.warmup_s
            with p.step("render", cost * self.history_frames, config.name):
                if timed_first:
                    timing = timed_frames(r, s.timing_frames, s.warmup, 0.0, self.pool.quiet)
                else:
                    for _ in range(self.history_frames):
                        r.render()
            for k in range(s.frames):
                with p.step("render", cost * config.accumulate, config.name):
                    if config.accumulate > 1:
                        for n in accumulators:
                            r.compiled.passes[n].reset()
                    for _ in range(config.accumulate):
                        r.render()
                    image = r.read_output(pin, flip_y=True)
                judged.append(self.judge_later(image, ref.image, name, maps=k == 0, hdrflip=self._hdrflip(k)))
                if k == 0:
                    first = image
            if not timed_first:
                with p.step("render", cost * self.history_frames, config.name):
                    timing = timed_frames(r, s.timing_frames, s.warmup, self.warmup_s, self.pool.quiet)
            self.method = timing.method
        settings = config.settings(self.scene)
        motion = self.motion_row(config, motion_refs, cost) if s.motion else None
        floor = self.floor_row(config, ref, cost, floor) if s.floors else None

        def finish() -> Row:
            samples, negatives, first_maps = {m: [] for m in s.metrics}, 0, {}
            for k, pending in enumerate(judged):
                per_view, maps, bad = pending.get()
                negatives += bad
                for m, v in per_view.items():
                    samples[m].append(v)
                if k == 0:
                    first_maps = maps
            samples = {m: v for m, v in samples.items() if v}
            row = Row(config.name, settings, timing.frame_ms, timing.pass_ms, timing.cpu_ms, s.frames,
                      len(self.view_set), tuple(self.view_set.size), summarize(samples), image=first,
                      maps=first_maps, negative_values=negatives)
            if motion:
                row.motion, row.motion_image = motion()
            if floor:
                row.floor, row.floor_image = floor()
            if path is not None:
                store_row(path, row)
            return row

        pending = judged + (motion.pending if motion else []) + (floor.pending if floor else [])
        finish.ready = lambda: all(q.done() for q in pending)
        return finish

    def motion_row(self, config: Config, motion_refs: dict, cost: float):
        """`config` along the trajectory, its sampled frames handed to the metric pool: returns
        the function that waits for them and gives (motion dict, last judged image)."""
        from ..renderer import Renderer

        s, p = self.s, self.progress
        graph = config.build_graph()
        pin = config.output_pin(graph)
        judged, last = [], None
        label = f"{config.name} in motion"
        with p.step("setup", 1, label):
            r = Renderer(self.scene, graph, views=self.view_set, gpu=self.gpu, first_frame=MOTION_FIRST_FRAME,
                         gpu_scene=self.loaded_scene())
        with r:
            for i, views in enumerate(along(self.motion_frames)):
                with p.step("render", cost, label):
                    r.render(views)
                    image = r.read_output(pin, flip_y=True) if i in motion_refs else None
                if image is not None:
                    judged.append(self.judge_later(image, motion_refs[i].image, f"config '{config.name}' frame {i}",
                                                   hdrflip=s.hdrflip_frames is None))
                    last = image

        def finish():
            samples, negatives = {m: [] for m in s.metrics}, 0
            for pending in judged:
                per_view, _, bad = pending.get()
                negatives += bad
                for m, v in per_view.items():
                    samples[m].append(v)
            samples = {m: v for m, v in samples.items() if v}
            return {**s.motion.as_dict(), **summarize(samples), "negative_values": negatives}, last

        finish.pending = judged
        return finish

    def floor_row(self, config: Config, ref: Reference, cost: float, floor=None):
        """`config`'s bias floor (rayvr.study.floor), judged in the metric pool: returns the
        function that waits for it and gives (floor dict, floor image)."""
        frames = self._floor_frames(config)
        label = f"{config.name} converged (bias floor)"
        if floor is None and self._floor_cached(config):
            floor = bias_floor(self.scene, config, self.view_set, frames, self.cache_dir, self.gpu)
        elif floor is None:
            with self.progress.step("render", cost * frames, label) as tick:
                floor = bias_floor(self.scene, config, self.view_set, frames, self.cache_dir, self.gpu,
                                   tick=lambda n: tick(n / frames))
            if self.keep_floors and self.cache_dir is False:
                self.new_floors[config.name] = floor
        out = floor.against(ref)
        pending = self.judge_later(floor.image, ref.image, f"floor of '{config.name}'",
                                   hdrflip=self.s.hdrflip_frames is None)

        def finish():
            per_view, _, _ = pending.get()
            out.update({m: float(np.mean(v)) for m, v in per_view.items()})
            return out, floor.image

        finish.pending = [pending]
        return finish

    # -- progressive curves ------------------------------------------------------------------
    def curve_graphs(self) -> list:
        """(name, builder options) of the progressive renders: raw path tracing and, where the
        path-traced graph takes `denoise=`, each denoiser."""
        from .configs import available_denoisers

        base = {"spp": 1, "max_bounces": self.ref_settings.max_bounces}
        return [("path tracing + Accumulate", base)] + [
            (f"path tracing + Accumulate + {d.upper()}", {**base, "denoise": d})
            for d in available_denoisers(path_traced_graph)]

    def curve(self, name: str, options: dict, ref: Reference):
        """The progressive curve of `path_traced_graph(**options)` (rayvr.study.progressive)."""
        return self.curve_later(name, options, ref)()

    def curve_later(self, name: str, options: dict, ref: Reference):
        """`curve` rendered, its snapshots handed to the metric pool: returns the function that
        waits for their judgements and gives the Curve."""
        from .progressive import progressive_curve

        s, cost = self.s, self._curve_cost()

        def step(kind, units, label):
            return self.progress.step(kind, units * cost if kind == "render" else units, label)

        return progressive_curve(self.scene, name, path_traced_graph(**options), options, self.view_set,
                                 s.progressive_frames, ref, self.judge_curve, s.timing_frames, s.warmup,
                                 self.warmup_s, PROGRESSIVE_FIRST_FRAME, self.gpu, step=step, later=True,
                                 quiet=self.pool.quiet)
