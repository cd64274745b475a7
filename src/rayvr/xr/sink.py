"""Where frames go: the `Sink` interface that `rv.Renderer` drives, and fixed offscreen views.

A frame, as the renderer sees it:

    sink.open(gpu)
    while (request := sink.wait_frame()) is not None:
        if request.should_render:
            ... render request.views into a texture array (one layer per view) ...
            request.render_time_s = gpu_ms / 1000     # optional: the sink's compositor uses it
            sink.submit(texture_array, request)
        else:
            sink.submit(None, request)                 # the runtime still needs the frame ended
    sink.close()
"""
from __future__ import annotations

import abc
import dataclasses

import numpy as np

from ..errors import XrError
from .views import Pose, ViewSet


@dataclasses.dataclass
class FrameRequest:
    """One frame the sink wants: its views and when it will be shown.

    `predicted_display_time` is in seconds on the sink's clock (simulated for SimulatedHeadset,
    the runtime's XrTime / 1e9 for OpenXR). `render_time_s` may be set by the renderer before
    `submit()` (its GPU time for this frame); sinks that model timing use it.
    """

    index: int
    views: ViewSet
    predicted_display_time: float
    head_pose: Pose | None = None
    should_render: bool = True
    render_time_s: float | None = None
    sink_data: dict = dataclasses.field(default_factory=dict)   # the sink's own per-frame state


class Sink(abc.ABC):
    """A consumer of rendered views: a headset (simulated or OpenXR) or fixed offscreen cameras."""

    @property
    @abc.abstractmethod
    def view_count(self) -> int:
        """Layers of the texture array `submit()` expects."""

    @property
    @abc.abstractmethod
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels of each view."""

    @abc.abstractmethod
    def open(self, gpu) -> None:
        """Bind to rayvr's GPU context (rayvr.gpu.GpuContext) before the first frame."""

    @abc.abstractmethod
    def wait_frame(self) -> FrameRequest | None:
        """Block until the next frame should start; None when the session or sequence ends."""

    @abc.abstractmethod
    def submit(self, texture_array, request: FrameRequest) -> None:
        """Hand over the rendered views (a TEXTURE_2D_ARRAY, layer i = view i)."""

    def close(self) -> None:
        """Release what `open()` took; safe to call twice."""

    @property
    def start_pose_given(self) -> bool:
        """False when the sink has no start pose of its own and wants one from the scene (a
        simulated headset built without one): the Renderer then calls place() before open()."""
        return True

    def place(self, pose: Pose) -> None:
        """Start the views at `pose` (the scene's camera): the hook behind start_pose_given."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class OffscreenViews(Sink):
    """Fixed cameras (the `rayvr render` case): the same ViewSet for `frames` frames.

    The last submitted texture array is kept in `last_texture`; `read()` reads it back.
    `frames=None` never ends (the caller stops asking).
    """

    def __init__(self, view_set: ViewSet, frames: int | None = 1):
        if frames is not None and frames < 0:
            raise XrError(f"OffscreenViews: frames must be >= 0 or None, got {frames}")
        self.view_set = view_set
        self.frames = frames
        self.last_texture = None
        self.submitted = 0
        self._issued = 0

    @property
    def view_count(self) -> int:
        return len(self.view_set)

    @property
    def size(self) -> tuple[int, int]:
        return self.view_set.size

    def open(self, gpu) -> None:
        self._issued = 0

    def wait_frame(self) -> FrameRequest | None:
        if self.frames is not None and self._issued >= self.frames:
            return None
        request = FrameRequest(self._issued, self.view_set, predicted_display_time=0.0)
        self._issued += 1
        return request

    def submit(self, texture_array, request: FrameRequest) -> None:
        if texture_array is not None:
            check_texture_array(texture_array, self, "OffscreenViews")
            self.last_texture = texture_array
        self.submitted += 1

    def read(self) -> np.ndarray:
        """The last submitted views as uint8 (views, height, width, channels), top row first."""
        from .readback import read_layers

        if self.last_texture is None:
            raise XrError("OffscreenViews.read(): nothing was submitted yet; run a frame first")
        return read_layers(self.last_texture)


def check_texture_array(texture_array, sink: Sink, who: str) -> None:
    """Raise XrError unless `texture_array` has the sink's per-view size and view count."""
    w, h = sink.size
    layers = getattr(texture_array, "layers", None)
    got = (texture_array.width, texture_array.height, layers)
    if got != (w, h, sink.view_count):
        raise XrError(f"{who}.submit(): expected a texture array of {w}x{h} with {sink.view_count} layers, "
                      f"got {got[0]}x{got[1]} with {got[2]} layers; render at the sink's size and view count")
