"""Error against run time: render each configuration, time it, compare it with a converged reference.

    results = rv.tune.measure(scene, rv.tune.standard_configs(scene), size=(64, 64), views=2)
    print(results.table())
    results.write("out/tune")          # table.md, results.csv, results.json, error_vs_ms_*.png

Timing is the render graph's profile (`rayvr.rendergraph.profile`): GPU timer queries where the
driver has them, else finish + wall clock per pass (llvmpipe); `Results.method` says which. The
frame time is the sum of the per-pass means over the timed frames (warm-up frames excluded,
which matters on llvmpipe: it compiles a shader at its first dispatch).
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..errors import OptionError
from . import metrics as M
from .configs import Config, effects_restored
from .reference import ReferenceSettings, reference_image
from .results import ConfigResult, Results


@dataclasses.dataclass
class Timing:
    """GPU ms per frame over the timed frames: total, per pass, and how it was measured."""

    frame_ms: float
    pass_ms: dict
    cpu_ms: float
    method: str
    frames: int


def warm_up(renderer, seconds: float) -> None:
    """Render until `seconds` have passed, so that a GPU which idled (an H100 drops to ~345 MHz)
    has its clocks up before anything is timed."""
    until = time.perf_counter() + seconds
    while time.perf_counter() < until:
        renderer.render()
        renderer.gl.finish()


def timed_frames(renderer, frames: int, warmup: int, warmup_s: float = 0.0) -> Timing:
    """Render untimed frames for `warmup_s` seconds (warm_up) and then `warmup` more, then
    `frames` timed frames; the per-pass means of the timed ones."""
    if frames < 1 or warmup < 0:
        raise OptionError(f"measure: frames must be >= 1 and warmup >= 0, got frames={frames}, warmup={warmup}")
    warm_up(renderer, warmup_s)
    for _ in range(warmup):
        renderer.render()
    renderer.gl.finish()
    compiled = renderer.compiled
    before = compiled.profile()
    for _ in range(frames):
        renderer.render()
    renderer.gl.finish()
    if renderer.compiled is not compiled:
        raise OptionError("measure: the graph recompiled during the timed frames; change materials before timing")
    after = compiled.profile()
    pass_ms = {name: _timed_mean(before.passes.get(name), stats, after.window) for name, stats in after.passes.items()}
    cpu = _timed_mean(before.cpu_ms, after.cpu_ms, after.window) if after.cpu_ms else float("nan")
    return Timing(float(sum(pass_ms.values())), pass_ms, cpu, after.method, frames)


def _timed_mean(before, after, window: int) -> float:
    """The mean of the samples added since `before` (rolling stats keep the last `window`)."""
    if before is None or after.samples >= window:
        return float(after.mean_ms)
    added = after.samples - before.samples
    if added <= 0:
        return float(after.mean_ms)
    return float((after.mean_ms * after.samples - before.mean_ms * before.samples) / added)


def make_views(scene, views=2, size=(256, 256)):
    """A ViewSet: `views` as given, or that many views from the scene's camera at `size`."""
    from ..renderer import default_views
    from ..xr.views import ViewSet

    if isinstance(views, ViewSet):
        return views
    if int(views) < 1:
        raise OptionError(f"views: need at least 1 view, got {views}")
    return default_views(scene, int(views), tuple(size))


def measure(scene, configs, reference=None, size=(256, 256), views=2, frames: int = 20, warmup: int = 3,
            reference_settings: ReferenceSettings | None = None, cache_dir=None, ppd: float | None = None,
            eps: float = 1e-2, metrics=tuple(M.METRICS), keep_images: bool = False, progress: bool = True,
            gpu=None, warmup_s: float = 0.0) -> Results:
    """Render every `Config` of `configs` over `scene` and return its GPU ms and image error.

    `reference`: a (views, h, w, c) linear image (row 0 at the top), an .npz file with an
    'image' array, or None to render the converged reference (cached, see
    rayvr.tune.reference). `views`: a ViewSet or a view count from the scene's camera, `size`
    per view. Error metrics: FLIP (HDR, `ppd` pixels per degree), relMSE (`eps`), PSNR of the
    sRGB-encoded images; `metrics` picks some (HDR-FLIP of a 1440x1600 view takes seconds of CPU).
    `warmup_s`: seconds of untimed frames before each configuration's `warmup` frames (the GPU
    idles while the CPU computes the previous configuration's error).
    The scene's material effects are restored afterwards."""
    from tqdm import tqdm

    from ..renderer import Renderer

    configs = check_configs(configs)
    metrics = M.check_metrics(metrics)
    view_set = make_views(scene, views, size)
    ref, ref_source = load_reference(scene, view_set, reference, reference_settings, cache_dir, gpu, progress)
    rows = []
    with effects_restored(scene):
        for config in tqdm(configs, desc="configurations", unit="config", disable=not progress, leave=False):
            assignment = config.apply(scene)
            graph = config.build_graph()
            pin = config.output_pin(graph)
            with Renderer(scene, graph, views=view_set, gpu=gpu) as r:
                timing = timed_frames(r, frames, warmup, warmup_s)
                image = r.read_output(pin, flip_y=True)
            errors = M.all_metrics(image, ref, ppd=ppd, eps=eps, names=(f"config '{config.name}' {pin}", "reference"),
                                   which=metrics)
            rows.append(ConfigResult(config.name, {k: v.name for k, v in assignment.items()}, dict(config.options),
                                     timing.frame_ms, timing.pass_ms, timing.cpu_ms, errors,
                                     image if keep_images else None))
    info = {"scene": scene.name, "views": len(view_set), "size": list(view_set.size), "frames": frames,
            "warmup": warmup, "warmup_s": warmup_s, "method": timing.method, "reference": ref_source, "ppd": ppd, "eps": eps}
    return Results(rows, info)


def check_configs(configs) -> list[Config]:
    """`configs` as a list: at least one, every one a Config, names unique."""
    configs = list(configs)
    if not configs:
        raise OptionError("measure: no configurations; pass e.g. rv.tune.standard_configs(scene)")
    names = [c.name for c in configs]
    if len(set(names)) != len(names):
        raise OptionError(f"measure: configuration names must be unique, got {names}")
    for c in configs:
        if not isinstance(c, Config):
            raise OptionError(f"measure: {c!r} is not a rayvr.tune.Config")
    return configs


def load_reference(scene, view_set, reference, settings, cache_dir, gpu, progress) -> tuple[np.ndarray, str]:
    """(image, where it came from) for `measure`'s `reference` argument."""
    from pathlib import Path

    if reference is None:
        settings = settings or ReferenceSettings()
        image, path = reference_image(scene, view_set, settings, cache_dir, gpu, progress)
        return image, str(path) if path else f"rendered ({settings.frames} frames x {settings.spp} spp)"
    if isinstance(reference, (str, Path)):
        path = Path(reference)
        if not path.exists():
            raise OptionError(f"reference {path}: no such file; pass an .npz with an 'image' array or None to render one")
        try:
            with np.load(path) as data:
                image = data["image"]
        except (OSError, ValueError, KeyError) as exc:
            raise OptionError(f"reference {path}: not an .npz with an 'image' array ({exc})") from None
        source = str(path)
    else:
        image, source = np.asarray(reference), "given array"
    image = M.as_views(image, "reference")
    if image.shape[:3] != (len(view_set), view_set.size[1], view_set.size[0]):
        raise OptionError(f"reference ({source}): {image.shape[0]} view(s) of {image.shape[2]}x{image.shape[1]}, "
                          f"but the measurement renders {len(view_set)} of {view_set.size[0]}x{view_set.size[1]}")
    return image, source
