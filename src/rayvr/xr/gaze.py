"""Where the eyes look over time: fixations joined by saccades (the simulated eye tracker), and
a gaze direction expressed in each view's eye space (`ViewSet.gaze`, which foveation reads).

A gaze is (x, y) in degrees in the head's frame: x to the right and y up of straight ahead, as
the angles whose tangents give the direction (tan x, tan y, -1). A `GazePath` holds each
fixation from its start time until a saccade takes the eyes to the next one; a saccade lasts
about 21 ms + 2.2 ms per degree of amplitude (the main sequence) and moves with a smooth
(smoothstep) velocity profile, ending at the next fixation's start.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import XrError
from . import quaternion

SACCADE_BASE_S = 0.021
SACCADE_S_PER_DEG = 0.0022


def saccade_duration(amplitude_deg: float) -> float:
    """Seconds a saccade of `amplitude_deg` takes (the main sequence, linear fit)."""
    return SACCADE_BASE_S + SACCADE_S_PER_DEG * abs(float(amplitude_deg))


class GazePath:
    """Fixations [(t_start_s, (x_deg, y_deg)), ...], times increasing; before the first the eyes
    hold it, after the last they stay there."""

    def __init__(self, fixations):
        times, points = [], []
        for i, entry in enumerate(fixations):
            try:
                t, (x, y) = entry
                t, x, y = float(t), float(x), float(y)
            except (TypeError, ValueError):
                raise XrError(f"GazePath: fixation {i} is {entry!r}; give (t_seconds, (x_deg, y_deg))") from None
            if not all(math.isfinite(v) for v in (t, x, y)) or max(abs(x), abs(y)) >= 89.0:
                raise XrError(f"GazePath: fixation {i} ({t}, ({x}, {y})): finite, and within 89 degrees of ahead")
            if times and t <= times[-1]:
                raise XrError(f"GazePath: fixation {i} starts at {t} s, not after {times[-1]} s; times must increase")
            times.append(t)
            points.append((x, y))
        if not times:
            raise XrError("GazePath: give at least one fixation (t_seconds, (x_deg, y_deg))")
        self.times = np.array(times)
        self.points = np.array(points)

    @classmethod
    def scan(cls, dwell_s: float = 0.3, amplitude_deg: float = 15.0) -> "GazePath":
        """A repeating scan: centre, then the four diagonals at `amplitude_deg`, `dwell_s` apart
        (twenty fixations)."""
        a = float(amplitude_deg)
        ring = [(0.0, 0.0), (a, a), (-a, a), (-a, -a), (a, -a)]
        return cls([(k * dwell_s, ring[k % len(ring)]) for k in range(20)])

    def direction_at(self, t: float) -> tuple[float, float]:
        """(x_deg, y_deg) at time `t` seconds."""
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        if i < 0:
            return tuple(self.points[0])
        if i + 1 < len(self.times):
            nxt = self.times[i + 1]
            span = saccade_duration(np.hypot(*(self.points[i + 1] - self.points[i])))
            start = max(nxt - span, self.times[i])
            if t > start:   # in the saccade towards the next fixation
                u = (t - start) / (nxt - start)
                s = u * u * (3.0 - 2.0 * u)
                return tuple((1.0 - s) * self.points[i] + s * self.points[i + 1])
        return tuple(self.points[i])


def make_gaze(spec) -> GazePath | None:
    """A GazePath from None (no eye tracker), "scan", "centre", a list of fixations, or one itself."""
    if spec is None or isinstance(spec, GazePath):
        return spec
    if spec == "scan":
        return GazePath.scan()
    if spec in ("centre", "center"):
        return GazePath([(0.0, (0.0, 0.0))])
    if isinstance(spec, (list, tuple)):
        return GazePath(spec)
    raise XrError(f"gaze {spec!r}: use None (no eye tracker), 'scan', 'centre', a list of fixations "
                  f"[(t_seconds, (x_deg, y_deg)), ...] or a rayvr.xr.gaze.GazePath")


def gaze_tangents(view_set, head_rotation, gaze_deg) -> np.ndarray:
    """(views, 2) tangents of the head-frame gaze `gaze_deg` (x, y degrees) in each view's eye
    space, for `ViewSet.gaze`; `head_rotation` the head's 3x3 rotation (world from head)."""
    x, y = np.radians(gaze_deg)
    d = np.array([math.tan(x), math.tan(y), -1.0])
    return direction_tangents(view_set, np.asarray(head_rotation, dtype=np.float64) @ d)


def direction_tangents(view_set, world_direction) -> np.ndarray:
    """(views, 2) tangents of a world-space gaze direction in each view's eye space."""
    d = np.asarray(world_direction, dtype=np.float64)
    rotations = quaternion.to_matrix(np.array([v.pose.orientation for v in view_set]))   # (views, 3, 3)
    eyes = np.einsum("vji,j->vi", rotations, d / np.linalg.norm(d))   # each eye's R^T d
    if (eyes[:, 2] >= -1e-6).any():
        raise XrError(f"gaze direction {tuple(d)}: points beside or behind a view; keep it within the views' "
                      f"half space")
    return eyes[:, :2] / -eyes[:, 2:3]
