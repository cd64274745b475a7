"""A recorded camera path: one head pose per frame plus the camera that saw it (IPD, fields of view).

The file is a pose log (see `trajectory.py`), so `SimulatedHeadset(trajectory="path.json")` plays
it back in time, with optional camera fields beside the poses:

    {"poses": [{"t": 0.0, "position": [x, y, z], "orientation": [x, y, z, w]}, ...],
     "ipd": 0.063, "fov_left": [left, right, up, down], "fov_right": [...], "near": 0.05, "far": 1000}

Angles are signed degrees (XrFovf's order). `rayvr view` records such files; `rayvr render
--camera-path FILE` renders one frame per pose.
"""
from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from ..errors import OptionError, XrError
from .cameras import stereo_views
from .trajectory import _load_pose_log
from .views import Fov, Pose, View, ViewSet


@dataclasses.dataclass
class CameraPath:
    """Head poses at times (seconds), with the camera's IPD and per-eye fov when recorded."""

    times: list = dataclasses.field(default_factory=list)
    poses: list = dataclasses.field(default_factory=list)
    ipd: float | None = None
    fov_left: Fov | None = None
    fov_right: Fov | None = None
    near: float | None = None
    far: float | None = None

    def __len__(self) -> int:
        return len(self.poses)

    def append(self, t: float, pose: Pose) -> None:
        """Add the head pose of time `t` (seconds; nudged after the last one if it is not)."""
        t = float(t)
        if self.times and t <= self.times[-1]:
            t = self.times[-1] + 1e-6
        self.times.append(t)
        self.poses.append(Pose(pose.position.copy(), pose.orientation.copy()))

    def view_set(self, i: int, base: ViewSet) -> ViewSet:
        """The views of pose `i`: `base`'s count, size, clip planes and fields of view (mono or
        stereo), with this path's fov, IPD and clip planes where they were recorded."""
        v = base[0]
        near = self.near if self.near is not None else v.near
        far = self.far if self.far is not None else v.far
        fov_l = self.fov_left or v.fov
        pose = self.poses[i]
        if len(base) == 1:
            return ViewSet([View(pose, fov_l, v.width, v.height, near, far, v.reversed_z)])
        if len(base) == 2:
            fov_r = self.fov_right or base[1].fov
            ipd = self.ipd if self.ipd is not None else float(np.linalg.norm(base[1].pose.position - v.pose.position))
            return stereo_views(pose, ipd, fov_l, fov_r, (v.width, v.height), near, far, v.reversed_z)
        raise OptionError(f"a camera path replays 1 (mono) or 2 (stereo) views, not {len(base)}; "
                          f"use --views 1 or 2")

    def to_dict(self) -> dict:
        doc: dict = {"poses": [{"t": t, "position": [float(x) for x in p.position],
                                "orientation": [float(x) for x in p.orientation]}
                               for t, p in zip(self.times, self.poses)]}
        if self.ipd is not None:
            doc["ipd"] = float(self.ipd)
        for key in ("fov_left", "fov_right"):
            fov = getattr(self, key)
            if fov is not None:
                doc[key] = [float(a) for a in fov.degrees()]
        for key in ("near", "far"):
            if getattr(self, key) is not None:
                doc[key] = float(getattr(self, key))
        return doc

    def save(self, path) -> Path:
        """Write the path as JSON (atomically); an empty path is an error, not an empty file."""
        from ..fileio import write_text

        if not self.poses:
            raise OptionError(f"{path}: the camera path has no poses yet; record some frames first")
        return write_text(path, json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def load(cls, path) -> "CameraPath":
        """A path from a JSON pose log, with the camera fields when present; XrError naming the
        file and field otherwise."""
        path = Path(path)
        times, positions, orientations = _load_pose_log(path)
        doc = json.loads(path.read_text())
        doc = doc if isinstance(doc, dict) else {}
        out = cls([float(t) for t in times], [Pose(p, q) for p, q in zip(positions, orientations)])
        for key in ("ipd", "near", "far"):
            if key in doc:
                value = doc[key]
                if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                        and math.isfinite(value) and value > 0):
                    raise XrError(f"{path}: {key}: expected a positive number of metres, got {value!r}")
                setattr(out, key, float(value))
        for key in ("fov_left", "fov_right"):
            if key in doc:
                value = doc[key]
                ok = isinstance(value, list) and len(value) == 4 and all(
                    isinstance(a, (int, float)) and not isinstance(a, bool) and abs(a) < 90 for a in value)
                if not ok:
                    raise XrError(f"{path}: {key}: expected [left, right, up, down] in signed degrees "
                                  f"(each within +-90), got {value!r}")
                setattr(out, key, Fov.from_degrees(*value))
        return out
