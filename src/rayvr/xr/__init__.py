"""Views and stereo math, the simulated headset, the OpenXR sink, light-field output.

`OpenXRSink` loads on first use, so rayvr imports and renders without pyopenxr installed.
"""
from .camera_path import CameraPath
from .cameras import (DEFAULT_IPD, camera_grid, camera_pose, default_views, eye_poses, grid_for_views, lightfield_row,
                      look_at, mono_view, scene_frustum, stereo_views)
from .compositor import Compositor
from .presets import PRESETS, HeadsetPreset, get_preset
from .quilt import LOOKING_GLASS, QuiltLayout, compose_quilt, read_quilt, write_quilt_png
from .readback import read_layers
from .simulated import SimulatedHeadset
from .sink import FrameRequest, OffscreenViews, Sink
from .trajectory import PoseLog, Trajectory, make_trajectory
from .views import Fov, Pose, View, ViewSet, projection

__all__ = ["Fov", "Pose", "View", "ViewSet", "projection",
           "look_at", "eye_poses", "mono_view", "stereo_views", "camera_grid", "grid_for_views", "lightfield_row",
           "camera_pose", "scene_frustum", "default_views", "DEFAULT_IPD",
           "Sink", "FrameRequest", "OffscreenViews", "SimulatedHeadset", "Compositor",
           "PRESETS", "HeadsetPreset", "get_preset", "Trajectory", "PoseLog", "make_trajectory", "CameraPath",
           "compose_quilt", "read_quilt", "write_quilt_png", "QuiltLayout", "LOOKING_GLASS",
           "read_layers", "OpenXRSink"]


def __getattr__(name: str):
    if name == "OpenXRSink":
        from .openxr_sink import OpenXRSink

        return OpenXRSink
    raise AttributeError(f"module 'rayvr.xr' has no attribute '{name}'")
