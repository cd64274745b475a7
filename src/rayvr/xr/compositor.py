"""A VR compositor's frame pacing on a simulated clock: vsync, late frames, motion-to-photon.

The model (one frame in flight, as xrWaitFrame paces it):
- Vsyncs fall at k / refresh_hz. A frame starts at a vsync and samples the head pose then;
  it targets the next vsync, its *predicted display time* (+ the panel's `display_latency_s`).
- It finishes `render_time_s` later. Finished by its target vsync: shown on time.
- Late by up to `max_late_vsyncs`: the compositor showed the previous frame again (reprojected)
  at the missed vsyncs and shows this one, reprojected to the newer head pose, at the first
  vsync after it finished: counted *reprojected*. Later than that (or with
  `late_policy="drop"`): *dropped*, never shown.
- The next frame starts at the first vsync at or after this one finished.
- Every vsync that showed no new frame counts in `repeated_vsyncs`.
Motion-to-photon latency of a shown frame = its photon time - its pose sample time.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import OptionError

_EPS = 1e-9   # seconds: a frame finishing exactly at its vsync is on time


@dataclasses.dataclass
class FrameTiming:
    """One frame's clock: start (pose sample), target vsync and predicted display time."""

    index: int
    start_time: float
    target_vsync: int
    predicted_display_time: float
    status: str = "pending"              # on_time | reprojected | dropped
    render_time_s: float | None = None
    shown_vsync: int | None = None
    motion_to_photon_s: float | None = None


class Compositor:
    """Frame pacing and accounting for a display refreshing at `refresh_hz`."""

    LATE_POLICIES = ("reproject", "drop")

    def __init__(self, refresh_hz: float, late_policy: str = "reproject", max_late_vsyncs: int = 1,
                 display_latency_s: float = 0.0):
        if refresh_hz <= 0:
            raise OptionError(f"refresh_hz must be > 0, got {refresh_hz}")
        if late_policy not in self.LATE_POLICIES:
            raise OptionError(f"late_policy '{late_policy}' is unknown; use one of {', '.join(self.LATE_POLICIES)}")
        self.refresh_hz = float(refresh_hz)
        self.period = 1.0 / self.refresh_hz
        self.late_policy = late_policy
        self.max_late_vsyncs = int(max_late_vsyncs)
        self.display_latency_s = float(display_latency_s)
        self.frames: list[FrameTiming] = []
        self._next_start_vsync = 0

    def begin_frame(self) -> FrameTiming:
        """Start the next frame at the first free vsync; it targets the vsync after."""
        k = self._next_start_vsync
        timing = FrameTiming(len(self.frames), k * self.period, k + 1,
                             (k + 1) * self.period + self.display_latency_s)
        self.frames.append(timing)
        return timing

    def end_frame(self, timing: FrameTiming, render_time_s: float) -> FrameTiming:
        """Account a finished frame; returns it with its status."""
        if render_time_s < 0:
            raise OptionError(f"render_time_s must be >= 0 seconds, got {render_time_s}")
        timing.render_time_s = float(render_time_s)
        finish = timing.start_time + timing.render_time_s
        done_vsync = max(timing.target_vsync, math.ceil(finish / self.period - _EPS))
        late_by = done_vsync - timing.target_vsync
        if late_by == 0:
            timing.status = "on_time"
        elif self.late_policy == "reproject" and late_by <= self.max_late_vsyncs:
            timing.status = "reprojected"
        else:
            timing.status = "dropped"
        if timing.status != "dropped":
            timing.shown_vsync = done_vsync
            timing.motion_to_photon_s = done_vsync * self.period + self.display_latency_s - timing.start_time
        # xrWaitFrame releases the next frame at the first vsync at or after this one finished
        self._next_start_vsync = done_vsync
        return timing

    def stats(self) -> dict:
        """Counts and distributions so far (times in milliseconds)."""
        done = [f for f in self.frames if f.status != "pending"]
        shown = [f for f in done if f.shown_vsync is not None]
        elapsed_vsyncs = max((f.shown_vsync or f.target_vsync) for f in done) if done else 0
        counts = {s: sum(f.status == s for f in done) for s in ("on_time", "reprojected", "dropped")}
        return {
            "refresh_hz": self.refresh_hz,
            "frames": len(done),
            **counts,
            "vsyncs": elapsed_vsyncs,
            "repeated_vsyncs": elapsed_vsyncs - len(shown),
            "elapsed_s": elapsed_vsyncs * self.period,
            "displayed_fps": len(shown) / (elapsed_vsyncs * self.period) if elapsed_vsyncs else 0.0,
            "frame_time_ms": _summary([f.render_time_s for f in done]),
            "motion_to_photon_ms": _summary([f.motion_to_photon_s for f in shown]),
        }


def _summary(seconds: list[float]) -> dict:
    if not seconds:
        return {"mean": None, "p50": None, "p95": None, "p99": None, "max": None}
    ms = np.asarray(seconds, dtype=np.float64) * 1e3
    return {"mean": float(ms.mean()), "p50": float(np.percentile(ms, 50)), "p95": float(np.percentile(ms, 95)),
            "p99": float(np.percentile(ms, 99)), "max": float(ms.max())}
