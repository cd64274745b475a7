"""Deterministic head trajectories: a pose for any time, from a formula or a recorded JSON log.

A pose log is JSON: {"poses": [{"t": 0.0, "position": [x, y, z], "orientation": [x, y, z, w]}, ...]}
(or the list alone), times in seconds, increasing. Between samples the position is linearly
and the orientation spherically interpolated; before the first and after the last the pose holds.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..fileio import read_json
from ..errors import OptionError, XrError, did_you_mean
from . import quaternion
from .views import Pose


class Trajectory:
    """A head pose as a function of time (seconds since the session started)."""

    def pose_at(self, t: float) -> Pose:
        raise NotImplementedError


class Still(Trajectory):
    """The head does not move."""

    def __init__(self, start: Pose):
        self.start = start

    def pose_at(self, t: float) -> Pose:
        return Pose(self.start.position.copy(), self.start.orientation.copy())


class Turn(Trajectory):
    """Yaw back and forth about +Y: amplitude * sin(2 pi t / period), a head shake."""

    def __init__(self, start: Pose, amplitude_deg: float = 45.0, period_s: float = 4.0):
        self.start, self.amplitude, self.period = start, math.radians(amplitude_deg), period_s

    def pose_at(self, t: float) -> Pose:
        yaw = self.amplitude * math.sin(2 * math.pi * t / self.period)
        return self.start.compose(Pose(np.zeros(3), quaternion.from_axis_angle([0, 1, 0], yaw)))


class Walk(Trajectory):
    """Walk forward (the start pose's -Z) at `speed` m/s with a vertical head bob per step."""

    def __init__(self, start: Pose, speed: float = 1.4, bob_m: float = 0.02, step_hz: float = 1.8):
        self.start, self.speed, self.bob, self.step_hz = start, speed, bob_m, step_hz

    def pose_at(self, t: float) -> Pose:
        offset = [0.0, self.bob * math.sin(2 * math.pi * self.step_hz * t), -self.speed * t]
        return self.start.compose(Pose(offset))


class PoseLog(Trajectory):
    """A recorded trajectory, interpolated (see the module docstring for the format)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.times, self.positions, self.orientations = _load_pose_log(self.path)

    def pose_at(self, t: float) -> Pose:
        times = self.times
        if t <= times[0]:
            i, a = 0, 0.0
        elif t >= times[-1]:
            i, a = len(times) - 1, 0.0
        else:
            i = int(np.searchsorted(times, t, side="right")) - 1
            a = (t - times[i]) / (times[i + 1] - times[i])
        if a == 0.0:
            return Pose(self.positions[i].copy(), self.orientations[i].copy())
        p = (1 - a) * self.positions[i] + a * self.positions[i + 1]
        return Pose(p, quaternion.slerp(self.orientations[i], self.orientations[i + 1], a))


def _numbers(value, n: int, where: str, path: Path) -> np.ndarray:
    ok = isinstance(value, (list, tuple)) and len(value) == n and all(
        isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value)
    if not ok:
        raise XrError(f"{path}: {where}: expected {n} finite numbers, got {value!r}")
    return np.array(value, dtype=np.float64)


def _load_pose_log(path: Path):
    doc = read_json(path, str(path), XrError, "the pose log")
    poses = doc.get("poses") if isinstance(doc, dict) else doc
    if not isinstance(poses, list) or not poses:
        raise XrError(f"{path}: poses: expected a non-empty list of {{\"t\", \"position\", \"orientation\"}} "
                      f"objects (top level or under \"poses\")")
    times, positions, orientations = [], [], []
    for i, entry in enumerate(poses):
        where = f"poses[{i}]"
        if not isinstance(entry, dict):
            raise XrError(f"{path}: {where}: expected an object with t, position, orientation, got {entry!r}")
        for key in ("t", "position", "orientation"):
            if key not in entry:
                raise XrError(f"{path}: {where}.{key}: missing; every pose needs t (seconds), "
                              f"position [x, y, z] and orientation [x, y, z, w]")
        t = entry["t"]
        if not isinstance(t, (int, float)) or isinstance(t, bool) or not math.isfinite(t):
            raise XrError(f"{path}: {where}.t: expected a time in seconds, got {t!r}")
        if times and t <= times[-1]:
            raise XrError(f"{path}: {where}.t: times must increase, but {t} follows {times[-1]}")
        q = _numbers(entry["orientation"], 4, f"{where}.orientation", path)
        if np.linalg.norm(q) < 1e-9:
            raise XrError(f"{path}: {where}.orientation: a zero quaternion is no rotation; "
                          f"use [0, 0, 0, 1] for none")
        times.append(float(t))
        positions.append(_numbers(entry["position"], 3, f"{where}.position", path))
        orientations.append(quaternion.normalize(q))
    return np.array(times), np.array(positions), np.array(orientations)


TRAJECTORIES = {"still": Still, "turn": Turn, "walk": Walk}


def make_trajectory(spec, start: Pose) -> Trajectory:
    """A Trajectory from a name ("still", "turn", "walk"), a JSON pose-log path, or one itself."""
    if isinstance(spec, Trajectory):
        return spec
    if isinstance(spec, Path) or (isinstance(spec, str) and spec.lower().endswith(".json")):
        return PoseLog(spec)
    if spec in TRAJECTORIES:
        return TRAJECTORIES[spec](start)
    raise OptionError(f"trajectory '{spec}' is unknown{did_you_mean(str(spec), TRAJECTORIES)}; use one of "
                      f"{', '.join(TRAJECTORIES)} or the path of a JSON pose log (*.json)")
