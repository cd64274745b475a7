"""Camera controllers: fly (WASD + mouse look, with a speed) and orbit (about a target point).

Both keep the head's orientation as yaw (about world +Y) and pitch (about the head's x axis), so
switching between them keeps the view; roll is not kept. glTF's axes: the camera looks down -Z.

    fly:   W/S forward/back, A/D left/right, E/Q up/down (in the head's frame), Shift x4 speed,
           drag with the left or right mouse button to look, scroll to change the speed
    orbit: drag to turn about the target, scroll or W/S to move in and out, A/D/E/Q to pan
"""
from __future__ import annotations

import math

import numpy as np

from ..xr import quaternion
from ..xr.views import Pose
from .input import InputState

LOOK_RADIANS_PER_PIXEL = 0.005
FAST = 4.0                       # Shift multiplies the speed by this
MAX_PITCH = math.radians(89.0)
MODES = ("fly", "orbit")


def orientation(yaw: float, pitch: float) -> np.ndarray:
    """The unit quaternion of a head turned by `yaw` about +Y, then tilted by `pitch` about its x."""
    return quaternion.normalize(quaternion.multiply(quaternion.from_axis_angle([0, 1, 0], yaw),
                                                    quaternion.from_axis_angle([1, 0, 0], pitch)))


def yaw_pitch(pose: Pose) -> tuple[float, float]:
    """The yaw and pitch of `pose`'s viewing direction (its -Z), roll dropped."""
    f = pose.rotation_matrix() @ np.array([0.0, 0.0, -1.0])
    return math.atan2(-f[0], -f[2]), math.asin(max(-1.0, min(1.0, float(f[1]))))


def _axes(inp: InputState) -> np.ndarray:
    """(right, up, forward) from the held keys, each -1, 0 or 1."""
    return np.array([inp.held("D") - inp.held("A"), inp.held("E") - inp.held("Q"),
                     inp.held("W") - inp.held("S")], dtype=np.float64)


class FlyCamera:
    """A free camera: position, yaw, pitch and a speed in metres per second."""

    def __init__(self, pose: Pose, speed: float = 1.0):
        self.speed = float(speed)
        self.set_pose(pose)

    def set_pose(self, pose: Pose) -> None:
        self.position = np.array(pose.position, dtype=np.float64)
        self.yaw, self.pitch = yaw_pitch(pose)

    @property
    def pose(self) -> Pose:
        return Pose(self.position.copy(), orientation(self.yaw, self.pitch))

    def look(self, dx: float, dy: float) -> None:
        """Turn by a mouse motion of (dx, dy) pixels (right and down are positive)."""
        self.yaw -= dx * LOOK_RADIANS_PER_PIXEL
        self.pitch = max(-MAX_PITCH, min(MAX_PITCH, self.pitch - dy * LOOK_RADIANS_PER_PIXEL))

    def update(self, inp: InputState, dt: float) -> None:
        """Move by the held keys for `dt` seconds, look by the drag, change the speed by the scroll."""
        if inp.scroll:
            self.speed *= 1.2 ** inp.scroll
        if inp.drag_buttons & {0, 1} and inp.drag != (0.0, 0.0):
            self.look(*inp.drag)
        right, up, forward = _axes(inp)
        if right or up or forward:
            local = np.array([right, up, -forward])
            speed = self.speed * (FAST if inp.held("LEFT_SHIFT", "RIGHT_SHIFT") else 1.0)
            rot = quaternion.to_matrix(orientation(self.yaw, self.pitch))
            self.position += rot @ (local / np.linalg.norm(local)) * speed * dt


class OrbitCamera:
    """A camera on a sphere about `target`: distance, yaw and pitch."""

    def __init__(self, pose: Pose, target, speed: float = 1.0):
        self.speed = float(speed)
        self.set_pose(pose, target)

    def set_pose(self, pose: Pose, target) -> None:
        """Look from `pose` toward its viewing direction; the target is the point on that ray
        nearest to `target`, so the view does not jump."""
        self.yaw, self.pitch = yaw_pitch(pose)
        forward = self._forward()
        to_target = np.asarray(target, dtype=np.float64) - pose.position
        along = float(np.dot(to_target, forward))
        self.distance = along if along > 1e-3 else max(float(np.linalg.norm(to_target)), 1e-3)
        self.target = pose.position + forward * self.distance

    def _forward(self) -> np.ndarray:
        return quaternion.to_matrix(orientation(self.yaw, self.pitch)) @ np.array([0.0, 0.0, -1.0])

    @property
    def pose(self) -> Pose:
        return Pose(self.target - self._forward() * self.distance, orientation(self.yaw, self.pitch))

    def update(self, inp: InputState, dt: float) -> None:
        """Turn about the target by the drag; move in and out by the scroll and W/S; pan by A/D/E/Q."""
        if inp.drag_buttons & {0, 1} and inp.drag != (0.0, 0.0):
            self.yaw -= inp.drag[0] * LOOK_RADIANS_PER_PIXEL
            self.pitch = max(-MAX_PITCH, min(MAX_PITCH, self.pitch - inp.drag[1] * LOOK_RADIANS_PER_PIXEL))
        right, up, forward = _axes(inp)
        speed = self.speed * (FAST if inp.held("LEFT_SHIFT", "RIGHT_SHIFT") else 1.0)
        self.distance = max(1e-3, self.distance * 0.9 ** inp.scroll - forward * speed * dt)
        if right or up:
            rot = quaternion.to_matrix(orientation(self.yaw, self.pitch))
            self.target = self.target + rot @ np.array([right, up, 0.0]) * speed * dt


class CameraRig:
    """The viewer's camera: a fly and an orbit controller kept on the same view, a home pose to
    reset to, and the scene's centre as the orbit target."""

    def __init__(self, home: Pose, centre, speed: float):
        self.home = Pose(home.position.copy(), home.orientation.copy())
        self.centre = np.asarray(centre, dtype=np.float64)
        self.mode = "fly"
        self.fly = FlyCamera(home, speed)
        self.orbit = OrbitCamera(home, self.centre, speed)

    @property
    def controller(self):
        return self.fly if self.mode == "fly" else self.orbit

    @property
    def pose(self) -> Pose:
        return self.controller.pose

    @property
    def speed(self) -> float:
        return self.controller.speed

    @speed.setter
    def speed(self, value: float) -> None:
        self.fly.speed = self.orbit.speed = float(value)

    def set_mode(self, mode: str) -> None:
        """'fly' or 'orbit'; the new controller starts where the old one was."""
        if mode not in MODES:
            from ..errors import OptionError

            raise OptionError(f"camera mode '{mode}': use one of {', '.join(MODES)}")
        if mode == self.mode:
            return
        pose = self.pose
        self.mode = mode
        self.set_pose(pose)

    def set_pose(self, pose: Pose) -> None:
        """Put the current controller at `pose` (orbit: about the scene's centre)."""
        if self.mode == "fly":
            self.fly.set_pose(pose)
        else:
            self.orbit.set_pose(pose, self.centre)

    def reset(self) -> None:
        """Back to the home pose."""
        self.set_pose(self.home)

    def update(self, inp: InputState, dt: float) -> None:
        self.controller.update(inp, dt)
        self.fly.speed = self.orbit.speed = self.controller.speed
