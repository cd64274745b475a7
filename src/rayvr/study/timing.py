"""GPU time per frame of a render: the graph's profile over timed frames after a warm-up.

Timing is the render graph's profile (`rayvr.rendergraph.profile`): GPU timer queries where the
driver has them, else finish + wall clock per pass (llvmpipe); `Timing.method` says which. The
frame time is the sum of the per-pass means over the timed frames (warm-up frames excluded,
which matters on llvmpipe: it compiles a shader at its first dispatch).
"""
from __future__ import annotations

import contextlib
import dataclasses
import time

from ..errors import OptionError

GPU_WARM_UP_S = 0.5    # an idle GPU clocks down (to a sixth of its boost clock) and needs a moment of load
SETTLE_WINDOW_S = 0.1  # after the warm-up's seconds, frames are timed (wall clock) in windows this long...
SETTLE_TOLERANCE = 0.03   # ...until two windows' mean frame times agree this closely
MAX_SETTLE_S = 1.0     # at most this long more


@dataclasses.dataclass
class Timing:
    """GPU ms per frame over the timed frames: total, per pass, and how it was measured."""

    frame_ms: float
    pass_ms: dict
    cpu_ms: float
    method: str
    frames: int


def warm_up(renderer, seconds: float) -> None:
    """Render until `seconds` have passed, so that a GPU which idled has its clocks up before
    anything is timed; then on, in windows of SETTLE_WINDOW_S, until two windows' mean frame times
    agree within SETTLE_TOLERANCE or MAX_SETTLE_S more have passed (a fixed 0.5 s alone left a
    study's first rows reading up to 1.3x the later rows' G-buffer time)."""
    if seconds <= 0:
        return
    until = time.perf_counter() + seconds
    while time.perf_counter() < until:
        renderer.render()
        renderer.gl.finish()
    settle_until, last = time.perf_counter() + MAX_SETTLE_S, None
    while time.perf_counter() < settle_until:
        mean = _window_frame_s(renderer)
        if last is not None and abs(mean - last) <= SETTLE_TOLERANCE * last:
            return
        last = mean


def _window_frame_s(renderer) -> float:
    """Mean wall seconds per finished frame over one window of at least SETTLE_WINDOW_S (and 2 frames)."""
    t0, n = time.perf_counter(), 0
    while n < 2 or time.perf_counter() - t0 < SETTLE_WINDOW_S:
        renderer.render()
        renderer.gl.finish()
        n += 1
    return (time.perf_counter() - t0) / n


def timed_frames(renderer, frames: int, warmup: int, warmup_s: float = 0.0, quiet=None) -> Timing:
    """Render untimed frames for `warmup_s` seconds (warm_up) and then `warmup` more, then
    `frames` timed frames; the per-pass means of the timed ones. `quiet`: a context manager
    factory held around all of it (rayvr.study.pool.MetricPool.quiet: the metric workers paused)."""
    if frames < 1 or warmup < 0:
        raise OptionError(f"measure: frames must be >= 1 and warmup >= 0, got frames={frames}, warmup={warmup}")
    with quiet() if quiet is not None else contextlib.nullcontext():
        return _timed(renderer, frames, warmup, warmup_s)


def _timed(renderer, frames: int, warmup: int, warmup_s: float) -> Timing:
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


def default_warmup_s(gpu) -> float:
    """Seconds of untimed frames before timing: GPU_WARM_UP_S where timer queries time a real
    GPU (its clocks drop while the CPU computes metrics), none on llvmpipe (no clocks to raise)."""
    return GPU_WARM_UP_S if gpu.caps.timer_queries and not gpu.caps.is_software else 0.0


def make_views(scene, views=2, size=(256, 256)):
    """A ViewSet: `views` as given, or that many views from the scene's camera at `size`."""
    from ..xr.cameras import default_views
    from ..xr.views import ViewSet

    if isinstance(views, ViewSet):
        return views
    if int(views) < 1:
        raise OptionError(f"views: need at least 1 view, got {views}")
    return default_views(scene, int(views), tuple(size))
