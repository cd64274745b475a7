"""GPU timing: timer queries where the driver's are trustworthy, finish + wall clock elsewhere."""
from __future__ import annotations

import time

import moderngl


def timing_method(use_queries: bool) -> str:
    """The name profiles and compile reports give GpuTimer's way of measuring."""
    return "timer-query" if use_queries else "finish+wall"


class GpuTimer:
    """Times one span of GPU work per frame.

    With timer queries two queries alternate, so the result of frame N is read when frame N+2
    begins (no stall); without them `end()` calls `ctx.finish()` and measures wall time, which
    the profile labels. `take()` hands each finished measurement over once.
    """

    def __init__(self, gl: moderngl.Context, use_queries: bool):
        self.gl = gl
        self.use_queries = use_queries
        self.method = timing_method(use_queries)
        self._queries = [gl.query(time=True) for _ in range(2)] if use_queries else []
        self._pending = [False, False]
        self._slot = 0
        self._t0 = 0.0
        self._fresh = False
        self.last_ms: float | None = None

    def begin(self) -> None:
        """Start the span (with queries: first collect the result of the query this slot held)."""
        if self.use_queries:
            if self._pending[self._slot]:
                self._collect(self._slot)
            self._queries[self._slot].mglo.begin()
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
            self.last_ms, self._fresh = (time.perf_counter() - self._t0) * 1e3, True

    def _collect(self, slot: int) -> None:
        self.last_ms, self._fresh = self._queries[slot].elapsed / 1e6, True
        self._pending[slot] = False

    def take(self) -> float | None:
        """The time in ms measured since the last take(), or None when no new one finished."""
        if not self._fresh:
            return None
        self._fresh = False
        return self.last_ms

    def reset(self) -> None:
        """Forget pending and finished measurements (a timer handed to a new owner)."""
        if any(self._pending) and self.use_queries:
            self.gl.finish()
            for slot in (0, 1):
                if self._pending[slot]:
                    _ = self._queries[slot].elapsed   # drain the result so the query can restart
        self._pending = [False, False]
        self._slot, self._fresh, self.last_ms = 0, False, None

    def resolve(self) -> float | None:
        """Wait for the latest query's result (a stall), collect it for take(), and return the
        latest time in ms."""
        if self.use_queries:
            prev = self._slot ^ 1
            if self._pending[prev]:
                self._collect(prev)
        return self.last_ms


# moderngl cannot delete a query object, so timers are pooled per context and reused: a graph
# recompiled many times holds the same queries.
_pools: dict[int, list[GpuTimer]] = {}


def acquire_timer(gl: moderngl.Context, use_queries: bool) -> GpuTimer:
    """A GpuTimer from the context's pool (or a new one); give it back with release_timer()."""
    pool = _pools.setdefault(id(gl), [])
    for i, t in enumerate(pool):
        if t.use_queries == use_queries and t.gl is gl:
            return pool.pop(i)
    return GpuTimer(gl, use_queries)


def release_timer(timer: GpuTimer) -> None:
    """Return `timer` to its context's pool."""
    timer.reset()
    _pools.setdefault(id(timer.gl), []).append(timer)
