"""Views in OpenXR's terms: a pose and an asymmetric field of view per view, packed for the GPU.

Math is float64 on the CPU; `ViewSet.pack()` writes float32 matrices in render space (world minus
the frame origin), laid out as `glsl/views.glsl` declares.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

VIEW_STRUCT_FLOATS = 5 * 16 + 4 * 4   # five mat4 + four vec4 (std430)
HEADER_BYTES = 16                     # uvec4 frame_info


@dataclasses.dataclass
class Fov:
    """XrFovf: signed angles in radians (left and down are negative for a centred view)."""

    angle_left: float
    angle_right: float
    angle_up: float
    angle_down: float

    @classmethod
    def symmetric(cls, vertical_deg: float, aspect: float) -> "Fov":
        ty = math.tan(math.radians(vertical_deg) / 2)
        tx = ty * aspect
        return cls(-math.atan(tx), math.atan(tx), math.atan(ty), -math.atan(ty))

    def tangents(self) -> tuple[float, float, float, float]:
        """tan of (left, right, down, up), the order views.glsl uses."""
        return (math.tan(self.angle_left), math.tan(self.angle_right),
                math.tan(self.angle_down), math.tan(self.angle_up))


@dataclasses.dataclass
class Pose:
    """XrPosef: position (metres) and orientation as a unit quaternion (x, y, z, w)."""

    position: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = dataclasses.field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 1.0]))

    def rotation_matrix(self) -> np.ndarray:
        x, y, z, w = np.asarray(self.orientation, dtype=np.float64) / np.linalg.norm(self.orientation)
        return np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ])

    def matrix(self) -> np.ndarray:
        """Eye-to-world 4x4 (float64)."""
        m = np.eye(4)
        m[:3, :3] = self.rotation_matrix()
        m[:3, 3] = self.position
        return m


def projection(fov: Fov, near: float, far: float, reversed_z: bool = False) -> np.ndarray:
    """OpenGL projection for an asymmetric frustum (as the OpenXR GL samples build it)."""
    l, r, d, u = fov.tangents()
    m = np.zeros((4, 4))
    m[0, 0] = 2 / (r - l)
    m[0, 2] = (r + l) / (r - l)
    m[1, 1] = 2 / (u - d)
    m[1, 2] = (u + d) / (u - d)
    m[3, 2] = -1
    if reversed_z:  # infinite far plane, depth 1 at near, 0 at infinity (with glClipControl semantics)
        m[2, 2] = 0.0
        m[2, 3] = near
    else:
        m[2, 2] = -(far + near) / (far - near)
        m[2, 3] = -2 * far * near / (far - near)
    return m


@dataclasses.dataclass
class View:
    """One rendered view: pose, field of view, clip planes and pixel size."""

    pose: Pose
    fov: Fov
    width: int
    height: int
    near: float = 0.05
    far: float = 1000.0
    reversed_z: bool = False

    def view_matrix(self, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Render-space to eye-space, float64."""
        m = self.pose.matrix()
        m[:3, 3] -= np.asarray(origin, dtype=np.float64)
        return np.linalg.inv(m)

    def projection_matrix(self) -> np.ndarray:
        return projection(self.fov, self.near, self.far, self.reversed_z)


class ViewSet:
    """All views of one frame (1 mono, 2 stereo, N light field) and their GPU packing."""

    def __init__(self, views: list[View]):
        if not views:
            raise ValueError("a ViewSet needs at least one view")
        self.views = list(views)
        self._prev_view_proj: list[np.ndarray] | None = None

    def __len__(self) -> int:
        return len(self.views)

    def __getitem__(self, i: int) -> View:
        return self.views[i]

    @property
    def size(self) -> tuple[int, int]:
        return self.views[0].width, self.views[0].height

    def origin(self) -> np.ndarray:
        """The render-space origin: the mean eye position (float64)."""
        return np.mean([v.pose.position for v in self.views], axis=0)

    def pack(self, origin=None, frame_index: int = 0, sample_index: int = 0, flags: int = 0,
             jitter=(0.0, 0.0)) -> bytes:
        """The bytes of the views SSBO for this frame (see glsl/views.glsl)."""
        origin = self.origin() if origin is None else np.asarray(origin, dtype=np.float64)
        n = len(self.views)
        header = np.array([n, frame_index, sample_index, flags], dtype=np.uint32)
        body = np.zeros((n, VIEW_STRUCT_FLOATS), dtype=np.float32)
        current = []
        for i, v in enumerate(self.views):
            view = v.view_matrix(origin)
            proj = v.projection_matrix()
            vp = proj @ view
            current.append((vp, origin))
            prev = vp
            if self._prev_view_proj is not None and i < len(self._prev_view_proj):
                pvp, porigin = self._prev_view_proj[i]
                shift = np.eye(4)
                shift[:3, 3] = origin - porigin   # this frame's render space -> last frame's
                prev = pvp @ shift
            mats = [view, proj, vp, np.linalg.inv(view), prev]
            # GLSL is column-major: write each matrix transposed.
            body[i, :80] = np.concatenate([m.T.reshape(-1) for m in mats])
            eye = v.pose.position - origin
            body[i, 80:96] = [*eye, 1.0, *v.fov.tangents(), v.near, v.far, v.width, v.height,
                              jitter[0], jitter[1], 0.0, 0.0]
        self._prev_view_proj = current
        return header.tobytes() + body.tobytes()
