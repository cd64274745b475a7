"""Frame sequences along a head trajectory: the views of frame i, computable on any worker.

Every view of `base` (a stereo pair, a camera grid) keeps its place relative to `start` while
the head follows `trajectory` (rayvr.xr.trajectory: still, turn, walk or a pose log), sampled at
frame / fps seconds. Frame i's views depend on i alone, so a worker renders any frame range
without the frames before it.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..xr.views import Pose, View, ViewSet


@dataclasses.dataclass
class TrajectoryViews:
    """`base` views carried along `trajectory` (a Trajectory or a name/pose-log path made from
    `start`), `fps` frames per second, `frames` long."""

    base: ViewSet
    trajectory: object = "still"
    frames: int = 1
    fps: float = 90.0
    start: Pose | None = None

    def __post_init__(self):
        from ..errors import OptionError
        from ..xr.trajectory import make_trajectory

        if int(self.frames) < 1:
            raise OptionError(f"sequence frames: need at least 1, got {self.frames}")
        if not self.fps > 0:
            raise OptionError(f"sequence fps: must be > 0, got {self.fps}")
        if self.start is None:
            self.start = Pose(self.base.origin(), self.base[0].pose.orientation)
        self.trajectory = make_trajectory(self.trajectory, self.start)
        inv_start = np.linalg.inv(self.start.matrix())
        self._relative = np.stack([inv_start @ v.pose.matrix() for v in self.base])

    @property
    def view_count(self) -> int:
        return len(self.base)

    @property
    def size(self) -> tuple[int, int]:
        return self.base.size

    def views_at(self, frame: int, previous: ViewSet | None = None) -> ViewSet:
        """The ViewSet of frame `frame` (`previous`: the frame before, for motion vectors)."""
        head = self.trajectory.pose_at(frame / self.fps).matrix()
        world = head @ self._relative
        views = [View(Pose.from_matrix(m), v.fov, v.width, v.height, v.near, v.far, v.reversed_z)
                 for m, v in zip(world, self.base)]
        return ViewSet(views, previous)
