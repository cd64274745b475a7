"""Views in OpenXR's terms: a pose and an asymmetric field of view per view, packed for the GPU.

Math is float64 on the CPU; `ViewSet.pack()` writes float32 matrices in render space (world minus
the frame origin), laid out as `glsl/views.glsl` declares. Pixel coordinates are GL's: x to the
right, y up, (0, 0) the bottom-left corner of the image, pixel (i, j) centred at (i + 0.5, j + 0.5).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import XrError
from ..gpu.records import VIEW_DATA, VIEWS_HEADER_BYTES
from . import quaternion

VIEW_STRUCT_FLOATS = VIEW_DATA.size // 4   # floats per view record
HEADER_BYTES = VIEWS_HEADER_BYTES          # uvec4 frame_info
FLAG_REVERSED_Z = 1                   # frame_info.w bit: projections are reversed-Z (infinite far)


@dataclasses.dataclass
class Fov:
    """XrFovf: signed angles in radians (left and down are negative for a centred view)."""

    angle_left: float
    angle_right: float
    angle_up: float
    angle_down: float

    @classmethod
    def symmetric(cls, vertical_deg: float, aspect: float) -> "Fov":
        """A centred frustum from the vertical angle and the width/height aspect."""
        ty = math.tan(math.radians(vertical_deg) / 2)
        tx = ty * aspect
        return cls(-math.atan(tx), math.atan(tx), math.atan(ty), -math.atan(ty))

    @classmethod
    def from_degrees(cls, left: float, right: float, up: float, down: float) -> "Fov":
        """XrFovf from signed degrees (left/down negative), e.g. Fov.from_degrees(-52, 45, 48, -50)."""
        return cls(*(math.radians(a) for a in (left, right, up, down)))

    @classmethod
    def from_tangents(cls, left: float, right: float, down: float, up: float) -> "Fov":
        """XrFovf from the frustum's tangents (OpenVR's raw projection, in views.glsl's order)."""
        return cls(math.atan(left), math.atan(right), math.atan(up), math.atan(down))

    def tangents(self) -> tuple[float, float, float, float]:
        """tan of (left, right, down, up), the order views.glsl uses."""
        return (math.tan(self.angle_left), math.tan(self.angle_right),
                math.tan(self.angle_down), math.tan(self.angle_up))

    def degrees(self) -> tuple[float, float, float, float]:
        """(left, right, up, down) in degrees, XrFovf's order."""
        return tuple(math.degrees(a) for a in (self.angle_left, self.angle_right, self.angle_up, self.angle_down))

    def sheared(self, dx: float, dy: float) -> "Fov":
        """This frustum with its tangents shifted by (dx, dy): an off-axis (lens-shifted) copy."""
        l, r, d, u = self.tangents()
        return Fov.from_tangents(l + dx, r + dx, d + dy, u + dy)


@dataclasses.dataclass
class Pose:
    """XrPosef: position (metres) and orientation as a unit quaternion (x, y, z, w)."""

    position: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = dataclasses.field(default_factory=lambda: quaternion.IDENTITY.copy())

    def __post_init__(self):
        self.position = np.asarray(self.position, dtype=np.float64).reshape(3)
        self.orientation = np.asarray(self.orientation, dtype=np.float64).reshape(4)

    @classmethod
    def from_matrix(cls, m) -> "Pose":
        """The pose of a rigid 4x4 local-to-world matrix."""
        m = np.asarray(m, dtype=np.float64)
        return cls(m[:3, 3].copy(), quaternion.from_matrix(m[:3, :3]))

    def rotation_matrix(self) -> np.ndarray:
        """The orientation as a 3x3 rotation matrix (float64)."""
        return quaternion.to_matrix(self.orientation)

    def matrix(self) -> np.ndarray:
        """Eye-to-world 4x4 (float64)."""
        m = np.eye(4)
        m[:3, :3] = self.rotation_matrix()
        m[:3, 3] = self.position
        return m

    def compose(self, local: "Pose") -> "Pose":
        """`local` (given in this pose's frame) expressed in this pose's parent frame."""
        return Pose(self.position + self.rotation_matrix() @ local.position,
                    quaternion.normalize(quaternion.multiply(self.orientation, local.orientation)))

    def transform_point(self, p) -> np.ndarray:
        """A point given in this pose's frame, in the parent frame."""
        return self.rotation_matrix() @ np.asarray(p, dtype=np.float64) + self.position


def projection(fov: Fov, near: float, far: float, reversed_z: bool = False) -> np.ndarray:
    """OpenGL projection for an asymmetric frustum (as the OpenXR GL samples build it).

    Reversed-Z is the infinite-far form: depth 1 at `near`, 0 at infinity, for glClipControl
    (GL_LOWER_LEFT, GL_ZERO_TO_ONE) and a GL_GREATER depth test.
    """
    return _projections(np.array([fov.tangents()]), np.array([near], np.float64), np.array([far], np.float64),
                        np.array([reversed_z]))[0]


def _projections(tangents: np.ndarray, near: np.ndarray, far: np.ndarray, reversed_z: np.ndarray) -> np.ndarray:
    """`projection` of n views at once: tangents (n, 4) as Fov.tangents() orders them, the other
    arguments (n,); returns (n, 4, 4)."""
    l, r, d, u = tangents.T
    m = np.zeros((len(tangents), 4, 4))
    m[:, 0, 0] = 2 / (r - l)
    m[:, 0, 2] = (r + l) / (r - l)
    m[:, 1, 1] = 2 / (u - d)
    m[:, 1, 2] = (u + d) / (u - d)
    m[:, 3, 2] = -1
    std = ~reversed_z   # reversed-Z ignores `far` (it may be inf)
    n, f = near[std], far[std]
    m[std, 2, 2] = -(f + n) / (f - n)
    m[std, 2, 3] = -2 * f * n / (f - n)
    m[reversed_z, 2, 3] = near[reversed_z]
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
        return np.linalg.inv(self.inverse_view_matrix(origin))

    def inverse_view_matrix(self, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Eye-space to render-space, float64."""
        m = self.pose.matrix()
        m[:3, 3] -= np.asarray(origin, dtype=np.float64)
        return m

    def projection_matrix(self) -> np.ndarray:
        """This view's OpenGL projection (see `projection`)."""
        return projection(self.fov, self.near, self.far, self.reversed_z)

    def project(self, points, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Pixel coordinates (x, y) and NDC depth of world (or render-space, with `origin`) points.

        Returns an array (..., 3): x and y in pixels from the bottom-left corner, z in NDC.
        """
        p = np.asarray(points, dtype=np.float64)
        ph = np.concatenate([p, np.ones(p.shape[:-1] + (1,))], axis=-1)
        clip = ph @ (self.projection_matrix() @ self.view_matrix(origin)).T
        ndc = clip[..., :3] / clip[..., 3:4]
        return np.stack([(ndc[..., 0] + 1) * 0.5 * self.width,
                         (ndc[..., 1] + 1) * 0.5 * self.height, ndc[..., 2]], axis=-1)

    def primary_ray(self, pixel, origin=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
        """(origin, unit direction) through `pixel` (x, y): the CPU twin of view_primary_ray()."""
        l, r, d, u = self.fov.tangents()
        uvx, uvy = pixel[0] / self.width, pixel[1] / self.height
        dir_eye = np.array([l + (r - l) * uvx, d + (u - d) * uvy, -1.0])
        dir_eye /= np.linalg.norm(dir_eye)
        return (self.pose.position - np.asarray(origin, dtype=np.float64),
                self.pose.rotation_matrix() @ dir_eye)


class ViewSet:
    """All views of one frame (1 mono, 2 stereo, N light field) and their GPU packing.

    `previous`: last frame's ViewSet, whose packed view-projections become this frame's
    `prev_view_proj` (motion vectors) when the view count matches.
    """

    def __init__(self, views: list[View], previous: "ViewSet | None" = None):
        if not views:
            raise XrError("a ViewSet needs at least one view; pass a list of rayvr.xr.View")
        sizes = {(v.width, v.height) for v in views}
        if len(sizes) != 1:
            raise XrError(f"all views of a ViewSet render into one texture array, but their sizes differ: "
                          f"{sorted(sizes)}; give every View the same width and height")
        self.views = list(views)
        self._prev_view_proj = previous._prev_view_proj if previous is not None else None
        # the index of views[0] in its whole frame (a share of a frame split by views): the
        # shaders' random streams follow the global index (views.glsl view_global_index)
        self.first_view_index = 0
        self._gaze = None

    @property
    def gaze(self) -> np.ndarray | None:
        """Where each eye looks, as (views, 2) tangents (x right, y up) of the gaze direction in
        that view's eye space, from an eye tracker; None when none is known (foveation then
        centres on each view's image: `gaze_tangents`)."""
        return self._gaze

    @gaze.setter
    def gaze(self, tangents) -> None:
        if tangents is None:
            self._gaze = None
            return
        g = np.asarray(tangents, dtype=np.float64)
        if g.shape != (len(self.views), 2) or not np.isfinite(g).all():
            raise XrError(f"ViewSet.gaze: expected ({len(self.views)}, 2) finite tangents (x right, y up) of each "
                          f"view's gaze direction, got shape {g.shape}")
        self._gaze = g

    def gaze_tangents(self) -> tuple[np.ndarray, bool]:
        """((views, 2) gaze tangents, tracked): the eye tracker's, or each image's centre."""
        from .foveation import centre_tangents

        return (self._gaze, True) if self._gaze is not None else (centre_tangents(self), False)

    def __len__(self) -> int:
        return len(self.views)

    def __getitem__(self, i: int) -> View:
        return self.views[i]

    def __iter__(self):
        return iter(self.views)

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of every view in pixels."""
        return self.views[0].width, self.views[0].height

    def origin(self) -> np.ndarray:
        """The render-space origin: the mean eye position (float64)."""
        return np.mean([v.pose.position for v in self.views], axis=0)

    def _columns(self) -> np.ndarray:
        """(n, 16) float64, a row per view: position, orientation, tangents, near, far, width,
        height, reversed_z: one pass over the views, so the matrices are built for all at once."""
        return np.array([(*v.pose.position, *v.pose.orientation, *v.fov.tangents(), v.near, v.far,
                          v.width, v.height, v.reversed_z) for v in self.views], dtype=np.float64)

    def matrices(self, origin=None) -> dict[str, np.ndarray]:
        """float64 (n, 4, 4) stacks: view, proj, view_proj, inv_view, in render space."""
        origin = self.origin() if origin is None else np.asarray(origin, dtype=np.float64)
        return self._matrices(origin, self._columns())

    def _matrices(self, origin: np.ndarray, c: np.ndarray) -> dict[str, np.ndarray]:
        inv_view = np.zeros((len(c), 4, 4))
        inv_view[:, :3, :3] = quaternion.to_matrix(c[:, 3:7])
        inv_view[:, :3, 3] = c[:, 0:3] - origin
        inv_view[:, 3, 3] = 1.0
        view = np.linalg.inv(inv_view)
        proj = _projections(c[:, 7:11], c[:, 11], c[:, 12], c[:, 15] != 0)
        return {"view": view, "proj": proj, "view_proj": proj @ view, "inv_view": inv_view}

    def restart_key(self, origin=None) -> bytes:
        """What progressive accumulation depends on: the render-space matrices as the GPU sees
        them (float32) and the render-space origin. A change restarts it: a head that only
        translates leaves the render-space matrices as they were but moves the origin."""
        origin = self.origin() if origin is None else np.asarray(origin, dtype=np.float64)
        m = self._matrices(origin, self._columns())
        mats = np.concatenate([m[k].astype(np.float32).reshape(-1) for k in ("view", "proj", "view_proj")])
        return mats.tobytes() + origin.tobytes() + np.int64(len(self.views)).tobytes()

    def pack(self, origin=None, frame_index: int = 0, sample_index: int = 0, flags: int = 0,
             jitter=(0.0, 0.0)) -> bytes:
        """The bytes of the views SSBO for this frame (see glsl/views.glsl)."""
        origin = self.origin() if origin is None else np.asarray(origin, dtype=np.float64)
        n = len(self.views)
        if self.views[0].reversed_z:
            flags |= FLAG_REVERSED_Z
        header = np.array([n, frame_index, sample_index, flags], dtype=np.uint32)
        c = self._columns()
        m = self._matrices(origin, c)
        prev = m["view_proj"]
        if self._prev_view_proj is not None and len(self._prev_view_proj[0]) == n:
            pvp, porigin = self._prev_view_proj
            shift = np.eye(4)
            shift[:3, 3] = origin - porigin   # this frame's render space -> last frame's
            prev = pvp @ shift
        self._prev_view_proj = (m["view_proj"], origin)
        body = VIEW_DATA.zeros(n)
        # GLSL is column-major: the record's mat4 fields are indexed [column, row]
        for name, x in (("view", m["view"]), ("proj", m["proj"]), ("view_proj", m["view_proj"]),
                        ("inv_view", m["inv_view"]), ("prev_view_proj", prev)):
            body[name] = x.transpose(0, 2, 1)
        body["eye"][:, :3] = m["inv_view"][:, :3, 3]
        body["eye"][:, 3] = 1.0
        body["fov_tan"] = c[:, 7:11]
        body["clip"] = c[:, 11:15]
        body["jitter"][:, :2] = jitter
        body["jitter"].view(np.uint32)[:, 2] = self.first_view_index + np.arange(n, dtype=np.uint32)
        if self._gaze is not None:
            body["gaze"][:, :2] = self._gaze
            body["gaze"][:, 2] = 1.0
        else:   # the image centres (foveation.centre_tangents, from the columns at hand)
            body["gaze"][:, 0] = (c[:, 7] + c[:, 8]) / 2
            body["gaze"][:, 1] = (c[:, 9] + c[:, 10]) / 2
        return header.tobytes() + body.tobytes()
