"""The viewer's eyes: how many views, their size, fields of view and IPD, from the scene's camera
or from a headset preset (rayvr.xr.presets)."""
from __future__ import annotations

import dataclasses
import math

from ..errors import OptionError
from ..xr.cameras import stereo_views
from ..xr.presets import get_preset
from ..xr.views import Fov, Pose, View, ViewSet

MIN_SIDE = 8


@dataclasses.dataclass
class ViewRig:
    """Per-view pixel size, view count (1 mono, 2 stereo), per-eye fov, IPD and clip planes.
    `preset` names the headset preset the size and fov came from (None: the scene's camera)."""

    views: int
    size: tuple[int, int]
    fov_left: Fov
    fov_right: Fov
    ipd: float
    near: float = 0.05
    far: float = 1000.0
    preset: str | None = None

    @classmethod
    def from_scene(cls, scene, views: int, size, ipd: float | None = None) -> "ViewRig":
        """The scene camera's fov and clip planes (as `rayvr render` uses them) at `size` per view."""
        from ..xr.cameras import DEFAULT_IPD, default_views

        if views not in (1, 2):
            raise OptionError(f"--views {views}: the viewer shows 1 (mono) or 2 (stereo) views")
        base = default_views(scene, 1, size)[0]
        return cls(views, (int(size[0]), int(size[1])), base.fov, base.fov,
                   DEFAULT_IPD if ipd is None else float(ipd), base.near, base.far)

    def view_set(self, head: Pose, previous: ViewSet | None = None) -> ViewSet:
        """This frame's views for the head pose; `previous` (last frame's) feeds motion vectors."""
        w, h = self.size
        if self.views == 1:
            views = [View(head, self.fov_left, w, h, self.near, self.far)]
        else:
            views = stereo_views(head, self.ipd, self.fov_left, self.fov_right, (w, h), self.near, self.far).views
        return ViewSet(views, previous=previous)

    def with_preset(self, name: str, scale: float = 1.0) -> "ViewRig":
        """The headset's per-eye fov, IPD and panel size times `scale` (the headset's panels are
        large for a software renderer); stereo."""
        p = get_preset(name)
        if not (0 < scale <= 1):
            raise OptionError(f"preset scale {scale}: use a factor in (0, 1]")
        size = tuple(max(MIN_SIDE, round(s * scale)) for s in p.eye_size)
        return dataclasses.replace(self, views=2, size=size, fov_left=p.left_fov, fov_right=p.right_fov,
                                   ipd=p.ipd, preset=name)

    def with_vertical_fov(self, degrees: float) -> "ViewRig":
        """A centred fov of `degrees` vertically at this size's aspect (leaves any preset)."""
        if not (1.0 <= degrees <= 170.0):
            raise OptionError(f"vertical fov {degrees} degrees: use 1 to 170")
        fov = Fov.symmetric(degrees, self.size[0] / self.size[1])
        return dataclasses.replace(self, fov_left=fov, fov_right=fov, preset=None)

    def with_size(self, size) -> "ViewRig":
        """Another per-view size, the fov's vertical angle kept (a preset's asymmetric fov is left)."""
        w, h = int(size[0]), int(size[1])
        if w < MIN_SIDE or h < MIN_SIDE:
            raise OptionError(f"view size {w}x{h}: at least {MIN_SIDE}x{MIN_SIDE} pixels")
        return dataclasses.replace(self, size=(w, h)).with_vertical_fov(self.vertical_fov_deg)

    @property
    def vertical_fov_deg(self) -> float:
        """The left eye's vertical field of view in degrees."""
        return math.degrees(self.fov_left.angle_up - self.fov_left.angle_down)
