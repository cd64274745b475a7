"""Frame timing shared by the benchmarks that time whole frames."""
from __future__ import annotations

import time

from rayvr.study.timing import GPU_WARM_UP_S
from rayvr.study.timing import warm_up as measure_warm_up


def wall_ms_per_frame(renderer, frames: int, warmup: int) -> float:
    """Wall ms per frame over `frames` renders, the GPU finished before and after."""
    gl = renderer.gl
    if frames > 5:          # not for smoke runs
        warm_up(renderer)
    for _ in range(warmup):
        renderer.render()
    gl.finish()
    renderer.profile()                  # the profile then covers the timed frames alone
    renderer.compiled.reset_profile()
    t0 = time.perf_counter()
    for _ in range(frames):
        renderer.render()
    gl.finish()
    return (time.perf_counter() - t0) / frames * 1e3


WARM_UP_S = GPU_WARM_UP_S   # an idle H100 clocks at ~345 MHz and needs a moment of load to reach ~1980 MHz


def warm_up(renderer, seconds: float = WARM_UP_S) -> None:
    """rayvr.study.timing.warm_up for the benchmarks' WARM_UP_S."""
    measure_warm_up(renderer, seconds)


