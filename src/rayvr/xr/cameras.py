"""Camera rigs that build ViewSets: look-at poses, mono and stereo views, N-view camera grids, and
the views a scene's own camera gives (`default_views`)."""
from __future__ import annotations

import math

import numpy as np

from ..errors import OptionError
from .views import Fov, Pose, View, ViewSet
from . import quaternion

DEFAULT_IPD = 0.063   # metres; the adult mean (Dodgson 2004)


def look_at(eye, target, up=(0.0, 1.0, 0.0)) -> Pose:
    """The pose of a camera at `eye` looking at `target` (glTF: the camera looks down its -Z)."""
    eye = np.asarray(eye, dtype=np.float64)
    forward = np.asarray(target, dtype=np.float64) - eye
    if np.linalg.norm(forward) == 0:
        raise OptionError("look_at: eye and target are the same point; give a target away from the eye")
    z = -forward / np.linalg.norm(forward)
    x = np.cross(np.asarray(up, dtype=np.float64), z)
    if np.linalg.norm(x) < 1e-12:
        raise OptionError("look_at: 'up' is parallel to the viewing direction; pass another up vector")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return Pose(eye, quaternion.from_matrix(np.column_stack([x, y, z])))


def eye_poses(head_pose: Pose, ipd: float) -> tuple[Pose, Pose]:
    """Left and right eye poses: the head pose moved -/+ IPD/2 along its own x axis."""
    half = 0.5 * float(ipd)
    return (head_pose.compose(Pose([-half, 0.0, 0.0])), head_pose.compose(Pose([half, 0.0, 0.0])))


def _size(size) -> tuple[int, int]:
    w, h = (int(size[0]), int(size[1]))
    if w <= 0 or h <= 0:
        raise OptionError(f"view size must be positive pixels (width, height), got {size!r}")
    return w, h


def mono_view(pose: Pose, fov: Fov, size, near: float = 0.05, far: float = 1000.0,
              reversed_z: bool = False) -> ViewSet:
    """One view (a desktop camera)."""
    w, h = _size(size)
    return ViewSet([View(pose, fov, w, h, near, far, reversed_z)])


def stereo_views(head_pose: Pose, ipd: float, fov_left: Fov, fov_right: Fov, size,
                 near: float = 0.05, far: float = 1000.0, reversed_z: bool = False) -> ViewSet:
    """Two views, left eye first (OpenXR's PRIMARY_STEREO order), each with its own fov."""
    w, h = _size(size)
    left, right = eye_poses(head_pose, ipd)
    return ViewSet([View(left, fov_left, w, h, near, far, reversed_z),
                    View(right, fov_right, w, h, near, far, reversed_z)])


def camera_grid(n_cols: int, n_rows: int, spacing, fov: Fov, size, center_pose: Pose | None = None,
                focal_distance: float | None = None, near: float = 0.05, far: float = 1000.0,
                reversed_z: bool = False, baseline=None) -> ViewSet:
    """An n_cols x n_rows grid of parallel cameras (Tauray's --camera-grid), for light fields.

    View i = row * n_cols + col; col 0 is the leftmost (-x) and row 0 the lowest (-y) camera, so
    a quilt with view 0 at the bottom-left shows the grid as seen from the front. `spacing` is
    metres between neighbours, one number or (x, y); or give `baseline` (metres from the first to
    the last camera, one number or (x, y)) and spacing=None. With `focal_distance`, each frustum is
    sheared (off-axis) so all views frame the same rectangle at that distance, as a Looking
    Glass expects: points on that plane land on the same pixel in every view.
    """
    if n_cols < 1 or n_rows < 1:
        raise OptionError(f"camera_grid: n_cols and n_rows must be >= 1, got {n_cols}x{n_rows}")
    if baseline is not None:
        bx, by = (float(baseline), float(baseline)) if np.isscalar(baseline) else map(float, baseline)
        spacing = (bx / max(n_cols - 1, 1), by / max(n_rows - 1, 1))
    if spacing is None:
        raise OptionError("camera_grid: give spacing (metres between cameras) or baseline (first to last)")
    sx, sy = (float(spacing), float(spacing)) if np.isscalar(spacing) else map(float, spacing)
    if focal_distance is not None and focal_distance <= 0:
        raise OptionError(f"camera_grid: focal_distance must be > 0 metres, got {focal_distance}")
    w, h = _size(size)
    center_pose = center_pose or Pose()
    views = []
    for row in range(n_rows):
        for col in range(n_cols):
            dx = (col - (n_cols - 1) / 2) * sx
            dy = (row - (n_rows - 1) / 2) * sy
            f = fov if focal_distance is None else fov.sheared(-dx / focal_distance, -dy / focal_distance)
            views.append(View(center_pose.compose(Pose([dx, dy, 0.0])), f, w, h, near, far, reversed_z))
    return ViewSet(views)


def lightfield_row(n_views: int, view_cone_deg: float, focal_distance: float, fov: Fov, size,
                   center_pose: Pose | None = None, **kwargs) -> ViewSet:
    """A horizontal row of sheared views spanning `view_cone_deg` seen from the focal plane.

    A Looking Glass display shows a horizontal-parallax light field over a view cone (about
    40 degrees for the Portrait, per Looking Glass Factory's documentation); view 0 is the
    leftmost. The baseline is 2 * focal_distance * tan(cone / 2).
    """
    if n_views < 1:
        raise OptionError(f"lightfield_row: n_views must be >= 1, got {n_views}")
    baseline = 2 * focal_distance * np.tan(np.radians(view_cone_deg) / 2)
    spacing = baseline / (n_views - 1) if n_views > 1 else 0.0
    return camera_grid(n_views, 1, (spacing, 0.0), fov, size, center_pose, focal_distance, **kwargs)


def grid_for_views(n_views: int) -> tuple[int, int]:
    """The camera grid (cols, rows) for `n_views` when none is given: the most square
    factorisation with cols >= rows and cols * rows == n_views (48: 8x6, 12: 4x3); a prime count
    is one horizontal row (7: 7x1)."""
    if n_views < 1:
        raise OptionError(f"grid_for_views: need at least 1 view, got {n_views}")
    rows = max(r for r in range(1, math.isqrt(n_views) + 1) if n_views % r == 0)
    return n_views // rows, rows


def camera_pose(scene) -> tuple[Pose, float]:
    """The scene's first camera (pose, vertical fov in radians), or one framing its bounds."""
    cams = getattr(scene, "cameras", None) or []
    if cams:
        cam = cams[0]
        m = np.asarray(cam.transform, dtype=np.float64)
        rot = m[:3, :3] / np.linalg.norm(m[:3, :3], axis=0)
        return Pose(m[:3, 3].copy(), quaternion.from_matrix(rot)), float(cam.yfov)
    lo, hi = np.asarray(scene.bounds(), dtype=np.float64)
    centre = 0.5 * (lo + hi)
    radius = max(float(np.linalg.norm(hi - lo)) * 0.5, 1e-3)
    yfov = math.radians(45.0)
    eye = centre + np.array([0.0, 0.0, radius / math.tan(yfov / 2) * 1.1])
    return look_at(eye, centre), yfov


def scene_frustum(scene, size) -> tuple[Pose, Fov, float, float, float]:
    """(pose, fov, near, far, focal distance) of the scene's camera at `size` pixels: what
    `default_views` and light-field quilts build their views from. The focal distance is the
    scene's centre as seen from the camera (light-field frusta converge there)."""
    w, h = int(size[0]), int(size[1])
    if w <= 0 or h <= 0:
        raise OptionError(f"size: {w}x{h} is not a positive pixel size; use e.g. 256x256")
    pose, yfov = camera_pose(scene)
    cam = (getattr(scene, "cameras", None) or [None])[0]
    lo, hi = np.asarray(scene.bounds(), dtype=np.float64)
    centre = float(np.linalg.norm(0.5 * (lo + hi) - pose.position))   # the camera's distance to the scene's centre
    if cam is None:   # the framing camera's near plane stays in front of a small scene (millimetres across)
        gap = centre - 0.5 * float(np.linalg.norm(hi - lo))
        near = min(0.05, max(0.1 * gap, 1e-6))
    else:
        near = getattr(cam, "znear", 0.05) or 0.05
    far = getattr(cam, "zfar", 1000.0) or 1000.0
    focal = max(centre, near * 2)
    return pose, Fov.symmetric(math.degrees(yfov), w / h), near, far, focal


def default_views(scene, views: int = 1, size=(256, 256), ipd: float = DEFAULT_IPD,
                  grid: tuple[int, int] | None = None) -> ViewSet:
    """Views from the scene's camera: 1 = mono, 2 = stereo (IPD apart), N = a camera grid
    (`grid` cols x rows, default the most square one of N views (`grid_for_views`), spacing ipd,
    frusta converging on the scene's centre)."""
    pose, fov, near, far, focal = scene_frustum(scene, size)
    w, h = int(size[0]), int(size[1])
    if views == 1 and grid is None:
        return ViewSet([View(pose, fov, w, h, near, far)])
    if views == 2 and grid is None:
        return stereo_views(pose, ipd, fov, fov, (w, h), near, far)
    if grid is None:
        grid = grid_for_views(views)
    if grid[0] * grid[1] != views:
        raise OptionError(f"--grid {grid[0]}x{grid[1]} has {grid[0] * grid[1]} views but --views is {views}; "
                          f"make cols x rows equal the view count")
    return camera_grid(grid[0], grid[1], ipd, fov, (w, h), center_pose=pose, focal_distance=focal,
                       near=near, far=far)
