"""Per-pass GPU time with rolling statistics over the last N frames."""
from __future__ import annotations

import collections
import dataclasses

import numpy as np


@dataclasses.dataclass
class PassStats:
    """Rolling statistics of one pass's time (ms) over the last `samples` frames."""

    last_ms: float
    mean_ms: float
    min_ms: float
    max_ms: float
    p95_ms: float
    samples: int

    # Short spellings: stats.mean == stats.mean_ms, ...
    last = property(lambda self: self.last_ms)
    mean = property(lambda self: self.mean_ms)
    min = property(lambda self: self.min_ms)
    max = property(lambda self: self.max_ms)
    p95 = property(lambda self: self.p95_ms)


@dataclasses.dataclass
class Profile:
    """`profile.passes[name].mean_ms`; `str()` is a table; `method` says how time was measured."""

    method: str                     # 'timer-query' | 'finish+wall' | 'off'
    frames: int
    window: int
    passes: dict[str, PassStats]
    cpu_ms: PassStats | None        # CPU time inside execute() (includes waits with finish+wall)
    # non-finite samples each counting pass set to 0 since compile (GPU counters: rendergraph.nonfinite)
    nonfinite: dict[str, int] = dataclasses.field(default_factory=dict)
    # rays the ray passes traced per view in the last frame whose GPU counters came back (a frame
    # or two late: rendergraph.ray_counters), and their sum; [] and 0 when no pass traces
    rays_per_view: list[int] = dataclasses.field(default_factory=list)
    rays_total: int = 0

    @property
    def total_ms(self) -> float:
        return sum(s.mean_ms for s in self.passes.values())

    def as_dict(self) -> dict:
        return dataclasses.asdict(self) | {"total_ms": self.total_ms}

    def __str__(self) -> str:
        head = f"GPU time per pass ({self.method}, mean/min/max/p95 over the last {self.window} frames; {self.frames} frames)"
        width = max([len(p) for p in self.passes] + [5])
        lines = [head, f"  {'pass':<{width}}  {'mean ms':>9} {'min':>9} {'max':>9} {'p95':>9}"]
        for name, s in self.passes.items():
            lines.append(f"  {name:<{width}}  {s.mean_ms:9.3f} {s.min_ms:9.3f} {s.max_ms:9.3f} {s.p95_ms:9.3f}")
        lines.append(f"  {'total':<{width}}  {self.total_ms:9.3f}")
        if self.cpu_ms:
            lines.append(f"  CPU in execute(): mean {self.cpu_ms.mean_ms:.3f} ms")
        if self.rays_per_view:
            per_view = ", ".join(str(n) for n in self.rays_per_view[:8]) + (", ..." if len(self.rays_per_view) > 8 else "")
            lines.append(f"  rays traced (last frame): {self.rays_total} in all; per view {per_view}")
        if self.nonfinite:
            lines.append("  non-finite samples set to 0 (all frames): "
                         + ", ".join(f"{p} {n}" for p, n in self.nonfinite.items()))
        return "\n".join(lines)


class RollingTimes:
    """The last `window` samples of one quantity."""

    def __init__(self, window: int):
        self.values: collections.deque = collections.deque(maxlen=window)

    def add(self, ms: float) -> None:
        self.values.append(ms)

    def stats(self) -> PassStats | None:
        if not self.values:
            return None
        a = np.fromiter(self.values, dtype=np.float64)
        return PassStats(float(a[-1]), float(a.mean()), float(a.min()), float(a.max()),
                         float(np.percentile(a, 95)), len(a))
