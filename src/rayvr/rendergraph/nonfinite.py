"""Non-finite sample counters: one GPU atomic counter per pass that scrubs radiance.

A pass whose shaders set NaN or Inf samples to 0 (`glsl/nonfinite.glsl`: `nonfinite_scrub`,
`nonfinite_count`) declares `COUNTS_NONFINITE = True`. The compiled graph owns one buffer with a
uint per such pass and binds that pass's 4 bytes at the atomic counter binding
`RAYVR_NONFINITE_COUNTER` before the pass runs (a glBindBufferRange per counting pass and frame).
Counts accumulate from compile (or `reset()`). Two ways to read them:
- `read()` (`CompiledGraph.nonfinite_counts()`): exact now, waits for the GPU (tests, the CLI at
  the end of a render);
- `latest()` (`CompiledGraph.profile()` and `report()`, which the viewer calls every frame): no
  wait. At the end of a frame (`frame_end()`) the counters are copied on the GPU into a staging
  buffer behind a fence, once the previous copy's fence has signalled (polled, never waited on)
  and its counts were taken; `latest()` polls the same way and answers the last counts taken
  (a frame or two old, as timer queries are).
"""
from __future__ import annotations

import numpy as np

from ..gpu.bindings import BINDINGS
from .late_readback import LateReadback, gl_proc

GL_ATOMIC_COUNTER_BUFFER = 0x92C0
GL_ATOMIC_COUNTER_BARRIER_BIT = 0x1000
GL_BUFFER_UPDATE_BARRIER_BIT = 0x200
BINDING = BINDINGS["RAYVR_NONFINITE_COUNTER"]


class NonFiniteCounters:
    """A uint counter for each of `names` (the passes that count), in one GL buffer."""

    def __init__(self, gl, names):
        self.gl = gl
        self.names = list(names)
        self.slot = {n: i for i, n in enumerate(self.names)}
        self.buffer = gl.buffer(reserve=4 * max(len(self.names), 1))
        self.late = LateReadback(gl, self.buffer.size) if self.names else None
        self._latest = {n: 0 for n in self.names}
        self.reset()

    def bind(self, name: str) -> None:
        """Make pass `name`'s counter the one its shaders' `rayvr_nonfinite` increments."""
        gl_proc("glBindBufferRange")(GL_ATOMIC_COUNTER_BUFFER, BINDING, self.buffer.glo, 4 * self.slot[name], 4)

    def frame_end(self) -> None:
        """After a frame's passes: copy the counters for `latest()` unless a copy is pending."""
        if self.late is None or not self._poll():
            return
        self.gl.memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT)
        self.late.start(lambda staging: self.gl.copy_buffer(staging, self.buffer))

    def latest(self) -> dict[str, int]:
        """The counts of the last copy whose fence has signalled (no wait)."""
        self._poll()
        return dict(self._latest)

    def _poll(self) -> bool:
        """Take the pending copy's counts if it has landed; True when none is pending."""
        if self.late is None or not self.late.pending:
            return True
        data = self.late.take()
        if data is None:
            return False
        self._latest = {n: int(c) for n, c in zip(self.names, np.frombuffer(data, np.uint32))}
        return True

    def reset(self) -> None:
        """Every counter back to 0 (the next pass's increments see it)."""
        self.gl.memory_barrier(GL_ATOMIC_COUNTER_BARRIER_BIT)
        self.buffer.clear()
        self.gl.memory_barrier(GL_ATOMIC_COUNTER_BARRIER_BIT)
        if self.late is not None:
            self.late.drop()   # a pending copy holds counts from before
        self._latest = {n: 0 for n in self.names}

    def read(self) -> dict[str, int]:
        """{pass: non-finite samples set to 0 since compile or reset} (waits for the GPU)."""
        if not self.names:
            return {}
        self.gl.memory_barrier(GL_ATOMIC_COUNTER_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT)
        self.late.drop()   # what a pending copy holds is older than this
        counts = np.frombuffer(self.buffer.read(size=4 * len(self.names)), np.uint32)
        self._latest = {n: int(c) for n, c in zip(self.names, counts)}
        return dict(self._latest)

    def release(self) -> None:
        self.buffer.release()
        if self.late is not None:
            self.late.release()


def nonfinite_lines(counts: dict[str, int]) -> list[str]:
    """One line per pass that set samples to 0, for the CLI's stderr."""
    return [f"{n} non-finite sample{'s' if n != 1 else ''} in pass {name} {'were' if n != 1 else 'was'} set to 0"
            for name, n in counts.items() if n]
