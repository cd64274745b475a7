"""Views along a headset trajectory, for judging configurations in motion.

Temporal methods (TAA, accumulation) look different on a moving head than on a still one: their
history is reprojected, their accumulation restarts. The study moves the study's views (from the
scene's camera) along a trajectory of rayvr.xr.trajectory ("turn": a head shake, "walk", or a
JSON pose log) at the headset's refresh rate, renders every frame, and judges the frames at
`samples` evenly spaced points against a reference rendered for exactly those views (one
converged reference per sampled frame, cached like the static one).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import OptionError


@dataclasses.dataclass(frozen=True)
class Motion:
    """`frames` frames along `trajectory` at `refresh_hz`; the error is judged at `samples` of
    them (evenly spaced, the last one included), each with its own reference."""

    trajectory: str = "turn"
    frames: int = 16
    samples: int = 2
    refresh_hz: float = 90.0

    def __post_init__(self):
        if not 1 <= self.samples <= self.frames:
            raise OptionError(f"motion: samples must be 1..frames ({self.frames}), got {self.samples}")
        if not self.refresh_hz > 0:
            raise OptionError(f"motion: refresh_hz must be > 0, got {self.refresh_hz}")

    def sample_frames(self) -> list[int]:
        """The judged frame numbers: evenly spaced, ending with the last frame (history built up)."""
        step = self.frames / self.samples
        return [int(round(step * (k + 1))) - 1 for k in range(self.samples)]

    def as_dict(self) -> dict:
        return {"trajectory": self.trajectory, "frames": self.frames, "sampled_frames": self.sample_frames(),
                "refresh_hz": self.refresh_hz}


def head_pose(view_set):
    """The head the views hang from: at their mean eye position, oriented like the first view."""
    from ..xr.views import Pose

    return Pose(view_set.origin(), view_set[0].pose.orientation.copy())


def trajectory_views(view_set, motion: Motion) -> list[list]:
    """The views of every frame (lists of View): `view_set` carried rigidly by the head along the
    trajectory."""
    from ..xr.trajectory import make_trajectory
    from ..xr.views import Pose, View

    head0 = head_pose(view_set)
    trajectory = make_trajectory(motion.trajectory, head0)
    to_head = np.linalg.inv(head0.matrix())
    frames = []
    for i in range(motion.frames):
        carry = trajectory.pose_at(i / motion.refresh_hz).matrix() @ to_head
        frames.append([View(Pose.from_matrix(carry @ v.pose.matrix()), v.fov, v.width, v.height, v.near, v.far,
                            v.reversed_z) for v in view_set])
    return frames


def along(frames: list[list]):
    """ViewSets of `frames` one after another, each made after the previous one was rendered, so
    that it carries the previous frame's matrices (motion vectors)."""
    from ..xr.views import ViewSet

    previous = None
    for views in frames:
        previous = ViewSet(views, previous=previous)
        yield previous
