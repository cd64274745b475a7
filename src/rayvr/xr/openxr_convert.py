"""Values across the pyopenxr boundary: XrPosef/XrFovf -> rayvr Pose/Fov, located views ->
ViewSet, and the typed XrCompositionLayerProjectionView array of a projection layer.

`xr` is the pyopenxr module, passed in so this file imports without it.
"""
from __future__ import annotations

from .views import Fov, Pose, View, ViewSet


def pose_from_xr(posef, world_from_space: Pose | None = None) -> Pose:
    """rayvr Pose (float64) of an XrPosef given in the reference space, placed in the world."""
    o, p = posef.orientation, posef.position
    pose = Pose([p.x, p.y, p.z], [o.x, o.y, o.z, o.w])
    return world_from_space.compose(pose) if world_from_space is not None else pose


def fov_from_xr(fovf) -> Fov:
    """rayvr Fov of an XrFovf."""
    return Fov(float(fovf.angle_left), float(fovf.angle_right), float(fovf.angle_up), float(fovf.angle_down))


def views_from_located(located, size, near: float, far: float, reversed_z: bool = False,
                       world_from_space: Pose | None = None, previous: ViewSet | None = None) -> ViewSet:
    """The ViewSet of xrLocateViews' XrView list (pose in the reference space, fov per view)."""
    w, h = size
    return ViewSet([View(pose_from_xr(v.pose, world_from_space), fov_from_xr(v.fov), w, h, near, far, reversed_z)
                    for v in located], previous=previous)


def projection_views(xr, located, sub_images, depth_infos=None):
    """A ctypes array of XrCompositionLayerProjectionView, each built by its constructor so that
    its `type` is XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW (a bare ctypes array carries type 0,
    which the core validation layer rejects). Pose and fov are the runtime's, as located."""
    items = []
    for i, v in enumerate(located):
        nxt = depth_infos[i] if depth_infos is not None else None
        items.append(xr.CompositionLayerProjectionView(pose=v.pose, fov=v.fov, sub_image=sub_images[i], next=nxt))
    return (xr.CompositionLayerProjectionView * len(items))(*items)


def xr_version(major: int, minor: int, patch: int = 0) -> int:
    """XR_MAKE_VERSION."""
    return ((major & 0xFFFF) << 48) | ((minor & 0xFFFF) << 32) | (patch & 0xFFFFFFFF)


def version_tuple(v: int) -> tuple[int, int, int]:
    """(major, minor, patch) of an XrVersion."""
    return (int(v) >> 48) & 0xFFFF, (int(v) >> 32) & 0xFFFF, int(v) & 0xFFFFFFFF
