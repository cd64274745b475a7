"""Rays traced per view: one GPU counter per view that the ray passes add to, read a frame late.

A pass whose shaders trace rays for the views' pixels declares `COUNTS_RAYS = True`: its programs
compile with `RQ_COUNT_RAYS 1`, so `glsl/ray_query.glsl` counts the queries each invocation
begins, and each kernel ends with `ray_count_commit(view)` (`glsl/ray_counters.glsl`), which adds
them to its view's counter, one image atomic per subgroup of one view. The counters are one r32ui
texture of views x SLOTS texels (a view's count is its column's sum: each workgroup adds to the
row its index picks, so that the atomics do not all meet at one address) at the fixed image unit `RAYVR_RAY_COUNTER_IMAGE` (bound before each
counting pass: other passes may use that unit), cleared at a frame's start. At its end they are
copied into a staging buffer behind a fence (`late_readback.py`), so `latest()` (the profile's
`rays_per_view`) answers the last frame whose copy has landed without waiting; `read()` waits.
"""
from __future__ import annotations

import numpy as np

from ..gpu.bindings import BINDINGS
from .late_readback import LateReadback, gl_proc

UNIT = BINDINGS["RAYVR_RAY_COUNTER_IMAGE"]
GL_TEXTURE_2D = 0x0DE1
GL_RED_INTEGER = 0x8D94
GL_UNSIGNED_INT = 0x1405
GL_TEXTURE_UPDATE_BARRIER_BIT = 0x100
GL_PIXEL_BUFFER_BARRIER_BIT = 0x80
# The GLSL extensions the commit's subgroup sum uses where the driver has them (else one atomic
# per invocation): `enable` leaves their macros undefined, and the code then takes the fallback.
SLOTS = 64   # counters per view (RAY_COUNT_SLOTS)
SHADER_HEADER = "\n".join(f"#extension GL_KHR_shader_subgroup_{e} : enable" for e in ("basic", "vote", "arithmetic"))


class RayCounters:
    """The rays each of `views` views' pixels traced in the last frame (see the module docstring)."""

    def __init__(self, gl, views: int):
        self.gl = gl
        self.views = int(views)
        self.texture = gl.texture((self.views, SLOTS), 1, dtype="u4")
        self.late = LateReadback(gl, 4 * self.views * SLOTS)
        self._latest = [0] * self.views

    def frame_begin(self) -> None:
        """Every counter to 0 for the frame about to run (after last frame's copy, in GL's order)."""
        gl_proc("glClearTexImage")(self.texture.glo, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, None)

    def bind(self) -> None:
        """Bind the counters at their image unit (before a counting pass: another may have used it)."""
        self.texture.bind_to_image(UNIT, read=True, write=True)

    def frame_end(self) -> None:
        """After a frame's passes: copy the counters for `latest()` unless a copy is in flight."""
        self.gl.memory_barrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_PIXEL_BUFFER_BARRIER_BIT)
        self._poll()
        if not self.late.pending:
            self.late.start(lambda staging: self.texture.read_into(staging))

    def _poll(self) -> None:
        data = self.late.take()
        if data is not None:
            self._latest = self._sums(data)

    def _sums(self, data: bytes) -> list[int]:
        rows = np.frombuffer(data, np.uint32)[:self.views * SLOTS].reshape(SLOTS, self.views)
        return rows.sum(axis=0, dtype=np.uint64).tolist()

    def latest(self) -> list[int]:
        """Rays per view of the last frame whose counts have come back (no wait: a frame or two old)."""
        self._poll()
        return list(self._latest)

    def read(self) -> list[int]:
        """Rays per view of the last frame executed (waits for the GPU)."""
        self.gl.memory_barrier(GL_TEXTURE_UPDATE_BARRIER_BIT)
        self.late.drop()
        self._latest = self._sums(self.texture.read())
        return list(self._latest)

    def release(self) -> None:
        self.late.release()
        self.texture.release()
