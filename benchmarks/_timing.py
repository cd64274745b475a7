"""Frame timing shared by the benchmarks that time whole frames."""
from __future__ import annotations

import time


def wall_ms_per_frame(renderer, frames: int, warmup: int) -> float:
    """Wall ms per frame over `frames` renders, the GPU finished before and after."""
    gl = renderer.gl
    for _ in range(warmup):
        renderer.render()
    gl.finish()
    t0 = time.perf_counter()
    for _ in range(frames):
        renderer.render()
    gl.finish()
    return (time.perf_counter() - t0) / frames * 1e3
