"""GPU timing: timer queries where the driver's are trustworthy, finish + wall clock elsewhere."""
from __future__ import annotations

import time

import moderngl


def timing_method(use_queries: bool) -> str:
    """The name profiles and compile reports give GpuTimer's way of measuring."""
    return "timer-query" if use_queries else "finish+wall"


class GpuTimer:
    """Times one span of GPU work per frame.

    With timer queries the result of frame N is read when frame N+1 begins (no stall);
    without them `end()` calls `ctx.finish()` and measures wall time, which the profile labels.
    """

    def __init__(self, gl: moderngl.Context, use_queries: bool):
        self.gl = gl
        self.use_queries = use_queries
        self.method = timing_method(use_queries)
        self._queries = [gl.query(time=True) for _ in range(2)] if use_queries else []
        self._pending = [False, False]
        self._slot = 0
        self._t0 = 0.0
        self.last_ms: float | None = None

    def begin(self) -> None:
        """Start the span (with queries: first collect the result of the query this slot held)."""
        if self.use_queries:
            q = self._queries[self._slot]
            if self._pending[self._slot]:
                self.last_ms = q.elapsed / 1e6
            q.mglo.begin()
        else:
            self.gl.finish()
            self._t0 = time.perf_counter()

    def end(self) -> None:
        """End the span: `last_ms` gets its time now (finish+wall), or when this query slot is
        begun again two spans later (queries)."""
        if self.use_queries:
            self._queries[self._slot].mglo.end()
            self._pending[self._slot] = True
            self._slot ^= 1
        else:
            self.gl.finish()
            self.last_ms = (time.perf_counter() - self._t0) * 1e3

    def resolve(self) -> float | None:
        """Wait for outstanding queries and return the latest time in ms."""
        if self.use_queries:
            prev = self._slot ^ 1
            if self._pending[prev]:
                self.last_ms = self._queries[prev].elapsed / 1e6
                self._pending[prev] = False
        return self.last_ms
