"""Measure a `rayvr.tune.budget.CostModel` on the GPU with one render per effect level.

Every material is set to one level at a time (RASTER first, as the base). From each render:
- GPU time per pass (the graph's profile, after a time-based warm-up on GPUs with timer queries:
  an idle GPU's clocks are low). The passes that dispatch over EffectCompaction's pixel lists
  (shadows, reflections, path tracing) cost in proportion to their pixels: material m's share of
  them is its pixel count over all geometry pixels. Passes the base already has change with the
  level too (direct lighting shrinks where rays light the pixels instead: on tauray to an eighth
  from all RASTER to all SHADOWS), and their change is shared the same way, so a
  level on every material is predicted as the probe measured it (taken as unchanged, they made
  the model's all-SHADOWS frame 0.9 ms dearer than the study's row). Passes the level adds that
  are not list-driven (compaction, accumulation) are the level's fixed overhead.
- The per-pixel error map against the trusted reference (rayvr.study.reference): FLIP of the
  displayed images at the headset's pixels per degree, or relMSE of the radiance, averaged over
  `trials` frames (their seeds differ), summed over each material's pixels (G-buffer effect ids
  name the material per pixel) and divided by all pixels, so the shares of a one-level render add
  up to its metric exactly.
"""
from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..materials.effect import Effect
from ..study.configs import Config, effects_restored
from ..study.timing import default_warmup_s, timed_frames
from .budget import CostModel

TUNE_METRICS = ("flip", "relmse")
NO_GEOMETRY = 0xFF


def list_driven_passes(graph) -> set[str]:
    """Passes fed by an EffectCompaction pass: their work scales with the pixels of their list."""
    compaction = {n for n, p in graph.passes.items() if type(p).__name__ == "EffectCompaction"}
    return {e.dst_pass for e in graph.edges if e.is_data and e.src_pass in compaction}


GBUFFER_PASSES = ("GBufferRaster", "GBufferRT", "GBufferAuto")   # all write the same `effect` word


def effect_pin(graph) -> str:
    """The G-buffer's effect-word pin ("Pass.effect"), which names each pixel's material."""
    for name, p in graph.passes.items():
        if type(p).__name__ in GBUFFER_PASSES:
            return f"{name}.effect"
    raise OptionError(f"tune: graph '{graph.name}' has no G-buffer pass ({', '.join(GBUFFER_PASSES)}), so pixels "
                      f"cannot be told apart by material; tune the hybrid graph (rayvr.tune.hybrid_graph)")


def check_metric(metric: str) -> str:
    if metric not in TUNE_METRICS:
        raise OptionError(f"tune: metric {metric!r} cannot be split per pixel; use one of {', '.join(TUNE_METRICS)}")
    return metric


class ErrorJudge:
    """Per-pixel error maps against a reference: `metric` of rayvr.study.metrics.evaluate. With a
    `pool` (a rayvr.study.pool.MetricPool) the maps are made in its worker processes while the
    GPU renders on (the same numbers)."""

    def __init__(self, reference, display, ppd: float, metric: str, eps: float, pool=None):
        self.reference, self.display, self.ppd, self.metric, self.eps = reference, display, ppd, metric, eps
        self.pool = pool

    def __getstate__(self):     # a cluster worker's copy judges in its own process
        return {**self.__dict__, "pool": None}

    @property
    def quiet(self):
        """The pool's `quiet` (its workers paused while the GPU is timed), or None."""
        return self.pool.quiet if self.pool is not None else None

    def map(self, image, name: str) -> np.ndarray:
        from ..study.display import clamp_negative
        from ..study.metrics import evaluate, pair

        image, _ = clamp_negative(image)   # judged as displayed (0), as the study judges
        if self.metric == "flip" and getattr(self, "_shown", None) is None:    # the displayed reference, made once
            self._shown = self.display(pair(self.reference.image, self.reference.image)[1])
        _, maps = evaluate(image, self.reference.image, self.display, self.ppd, self.eps, names=(name, "reference"),
                           which=(self.metric,), maps=True, shown_reference=getattr(self, "_shown", None))
        return maps[self.metric]

    def map_later(self, image, name: str):
        """`map` as a function that waits for it (made in the pool's workers meanwhile, if any)."""
        if self.pool is None:
            made = self.map(image, name)
            return lambda: made
        pending = self.pool.judge(image, self.reference.image, self.display, self.ppd, self.eps, (name, "reference"),
                                  (self.metric,), maps=True)
        return lambda: pending.get()[1][self.metric]

    def mean_map_later(self, renderer, pin: str, trials: int, name: str):
        """The error map averaged over the next `trials` frames, as a function that waits for it."""
        later = []
        for _ in range(trials):
            renderer.render()
            later.append(self.map_later(renderer.read_output(pin, flip_y=True), name))
        return lambda: sum(f() for f in later) / trials

    def mean_map(self, renderer, pin: str, trials: int, name: str) -> np.ndarray:
        """The error map averaged over the next `trials` frames."""
        return self.mean_map_later(renderer, pin, trials, name)()


def probe_cost_model(scene, view_set, builder, options: dict, judge: ErrorJudge, levels=tuple(Effect),
                     frames: int = 10, warmup: int = 3, warmup_s: float | None = None, trials: int = 2,
                     progress: bool = True, gpu=None):
    """(CostModel, HDR pin) for `scene` seen by `view_set` with graphs from `builder(**options)`
    (see the module docstring). The scene's effects are restored."""
    from tqdm import tqdm

    from ..gpu import get_context
    from ..renderer import Renderer

    gpu = gpu or get_context()
    warmup_s = default_warmup_s(gpu) if warmup_s is None else warmup_s
    check_metric(judge.metric)
    probe = Config("tune probe", graph=builder, options=dict(options))
    graph = probe.build_graph()
    pin, ids_pin = probe.output_pin(graph), effect_pin(graph)
    if ids_pin not in graph.outputs:
        graph.mark_output(ids_pin)
    scaled = list_driven_passes(graph)
    probe_levels = sorted({Effect.RASTER} | {Effect.parse(e, where="levels") for e in levels})
    names = scene.materials.names()
    times, errors = {}, {}
    with effects_restored(scene), Renderer(scene, graph, views=view_set, gpu=gpu) as r:
        for level in tqdm(probe_levels, desc="effect levels", unit="level", disable=not progress, leave=False):
            for m in scene.materials:
                m.effect = level
            # warm-up >= 1 frame: the level may recompile
            times[level] = timed_frames(r, frames, max(1, warmup), warmup_s, judge.quiet)
            errors[level] = judge.mean_map_later(r, pin, trials, f"all {level.name} {pin}")
            if level == Effect.RASTER:
                words = r.read_output(ids_pin, flip_y=True)[..., 0]
    errors = {level: made() for level, made in errors.items()}
    geometry = (words & 0xFF) != NO_GEOMETRY
    material = (words >> 8)[geometry].astype(np.int64)
    total = words.size
    pixels = np.bincount(material, minlength=len(names))[:len(names)]
    share = pixels / max(int(pixels.sum()), 1)
    base = times[Effect.RASTER]
    ms = {n: {} for n in names}
    err = {n: {} for n in names}
    overhead = {}
    for level in probe_levels:
        t = times[level]
        list_ms = sum(v for p, v in t.pass_ms.items() if p in scaled)
        list_ms += sum(t.pass_ms.get(p, 0.0) - v for p, v in base.pass_ms.items() if p not in scaled)
        overhead[level] = 0.0 if level == Effect.RASTER else sum(
            v for p, v in t.pass_ms.items() if p not in scaled and p not in base.pass_ms)
        per_material = np.bincount(material, weights=errors[level][geometry].astype(np.float64),
                                   minlength=len(names))[:len(names)] / total
        for i, n in enumerate(names):
            ms[n][level] = 0.0 if level == Effect.RASTER else float(list_ms * share[i])
            err[n][level] = float(per_material[i])
    rest = float(errors[Effect.RASTER][~geometry].sum() / total)
    model = CostModel(base.frame_ms, ms, err, overhead, rest, {n: int(pixels[i]) for i, n in enumerate(names)},
                      judge.metric, base.method)
    return model, pin


def render_assignment(scene, view_set, builder, options: dict, assignment: dict, judge: ErrorJudge, frames: int,
                      warmup: int, warmup_s: float | None, trials: int, gpu) -> tuple[float, float, str]:
    """(GPU ms per frame, error, timing method) of `assignment` rendered; effects restored after."""
    from ..gpu import get_context
    from ..renderer import Renderer

    gpu = gpu or get_context()
    warmup_s = default_warmup_s(gpu) if warmup_s is None else warmup_s
    config = Config("tuned", effects=dict(assignment), graph=builder, options=dict(options))
    with effects_restored(scene):
        config.apply(scene)
        graph = config.build_graph()
        pin = config.output_pin(graph)
        with Renderer(scene, graph, views=view_set, gpu=gpu) as r:
            timing = timed_frames(r, frames, max(1, warmup), warmup_s, judge.quiet)
            error = float(judge.mean_map(r, pin, trials, f"tuned {pin}").mean())
    return timing.frame_ms, error, timing.method
