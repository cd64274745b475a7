"""Measure a `rayvr.tune.budget.CostModel` on the GPU with one render per effect level.

Every material is set to one level at a time (RASTER first, as the base). From each render:
- GPU time per pass (the graph's profile). The passes that dispatch over EffectCompaction's pixel
  lists (shadows, reflections, path tracing) cost in proportion to their pixels: material m's
  share of them is its pixel count over all geometry pixels. Passes the level adds that are not
  list-driven (compaction, accumulation) are the level's fixed overhead. Passes the base already
  has are assumed unchanged (conservative: direct lighting shrinks when rays light a pixel).
- The per-pixel error map against the reference (FLIP or relMSE), summed over each material's
  pixels (G-buffer effect ids name the material per pixel) and divided by all pixels, so the
  shares of a one-level render add up to its metric exactly.
"""
from __future__ import annotations

import numpy as np

from ..errors import OptionError
from ..materials.effect import Effect
from . import metrics as M
from .budget import CostModel
from .configs import Config, effects_restored
from .measure import load_reference, timed_frames

TUNE_METRICS = ("flip", "relmse")
NO_GEOMETRY = 0xFF


def error_map(image, ref, metric: str, ppd, name: str) -> np.ndarray:
    """Per-pixel error (views, h, w) whose mean is the metric."""
    if metric == "flip":
        return M.flip_map(image, ref, "hdr", ppd, names=(name, "reference"))
    return M.rel_mse_map(image, ref, names=(name, "reference"))


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


def _check_metric(metric: str) -> str:
    if metric not in TUNE_METRICS:
        raise OptionError(f"tune: metric {metric!r} cannot be split per pixel; use one of {', '.join(TUNE_METRICS)}")
    return metric


def probe_cost_model(scene, view_set, builder, options: dict, metric: str = "flip", levels=tuple(Effect),
                     frames: int = 10, warmup: int = 3, reference=None, reference_settings=None, cache_dir=None,
                     ppd=None, progress: bool = True, gpu=None):
    """(CostModel, reference image, HDR pin) for `scene` seen by `view_set` with graphs from
    `builder(**options)`; see the module docstring. The scene's effects are restored."""
    from tqdm import tqdm

    from ..renderer import Renderer

    _check_metric(metric)
    ref, _ = load_reference(scene, view_set, reference, reference_settings, cache_dir, gpu, progress)
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
            timing = timed_frames(r, frames, max(1, warmup))   # >= 1: the level may recompile
            times[level] = timing
            image = r.read_output(pin, flip_y=True)
            errors[level] = error_map(image, ref, metric, ppd, f"all {level.name} {pin}")
            if level == Effect.RASTER:
                words = r.read_output(ids_pin, flip_y=True)[..., 0]
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
        overhead[level] = 0.0 if level == Effect.RASTER else sum(
            v for p, v in t.pass_ms.items() if p not in scaled and p not in base.pass_ms)
        per_material = np.bincount(material, weights=errors[level][geometry].astype(np.float64),
                                   minlength=len(names))[:len(names)] / total
        for i, n in enumerate(names):
            ms[n][level] = 0.0 if level == Effect.RASTER else float(list_ms * share[i])
            err[n][level] = float(per_material[i])
    rest = float(errors[Effect.RASTER][~geometry].sum() / total)
    model = CostModel(base.frame_ms, ms, err, overhead, rest, {n: int(pixels[i]) for i, n in enumerate(names)},
                      metric, base.method)
    return model, ref, pin


def render_assignment(scene, view_set, builder, options: dict, assignment: dict, ref, metric: str,
                      frames: int, warmup: int, ppd, gpu) -> tuple[float, float, str]:
    """(GPU ms per frame, error, timing method) of `assignment` rendered; effects restored after."""
    from ..renderer import Renderer

    config = Config("tuned", effects=dict(assignment), graph=builder, options=dict(options))
    with effects_restored(scene):
        config.apply(scene)
        graph = config.build_graph()
        pin = config.output_pin(graph)
        with Renderer(scene, graph, views=view_set, gpu=gpu) as r:
            timing = timed_frames(r, frames, max(1, warmup))
            image = r.read_output(pin, flip_y=True)
    return timing.frame_ms, float(error_map(image, ref, metric, ppd, f"tuned {pin}").mean()), timing.method
