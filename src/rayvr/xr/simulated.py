"""`SimulatedHeadset`: an offscreen stereo headset with real presets, trajectories and a compositor.

It paces frames on a simulated clock (see compositor.py), so tests and benchmarks are
deterministic; the time a frame took comes from the renderer (`request.render_time_s`, its GPU
time), else the constructor's `frame_time_s`, else wall time between wait_frame and submit.
What it is given can be written: per-eye PNGs, a side-by-side PNG and a video (that readback is
the "display"; leave `record_dir` unset when timing).
"""
from __future__ import annotations

import time
from pathlib import Path

from ..errors import OptionError, XrError
from .cameras import stereo_views
from .compositor import Compositor
from .gaze import gaze_tangents, make_gaze
from .presets import HeadsetPreset, get_preset
from .sink import FrameRequest, Sink, check_texture_array
from .trajectory import make_trajectory
from .views import Pose, ViewSet

DEFAULT_START = Pose([0.0, 1.6, 0.0])   # standing eye height, looking down -Z


class SimulatedHeadset(Sink):
    """A stereo headset without hardware.

    preset: "index", "quest2", "quest3", "vive_pro2" (rayvr.xr.presets) or a HeadsetPreset.
    refresh_hz: the panel rate (default: the preset's). trajectory: "still", "turn", "walk", a
    JSON pose-log path or a Trajectory. size: per-eye (width, height) overriding the preset's.
    frames: end the session (wait_frame -> None) after this many frames; None never ends.
    record_dir: write eye PNGs and a side-by-side PNG per frame there (every `record_every`).
    video: also write a video of the side-by-side frames: True (mp4 when imageio-ffmpeg is
    installed, else gif), "mp4" or "gif". frame_time_s: a fixed render time for every frame.
    gaze: a simulated eye tracker (rayvr.xr.gaze): "scan", "centre", fixations [(t_s, (x_deg,
    y_deg)), ...] or a GazePath; each frame's views then carry where the eyes look at its
    predicted display time (`ViewSet.gaze`, which foveation 'gaze' follows). None: no tracker.
    """

    def __init__(self, preset: str | HeadsetPreset = "index", refresh_hz: float | None = None,
                 trajectory="still", size=None, record_dir=None, video: bool | str = False,
                 frames: int | None = None, ipd: float | None = None, start_pose: Pose | None = None,
                 near: float = 0.05, far: float = 1000.0, reversed_z: bool = False,
                 frame_time_s: float | None = None, late_policy: str = "reproject",
                 max_late_vsyncs: int = 1, record_every: int = 1, encode_srgb: bool = False, gaze=None):
        self.preset = preset if isinstance(preset, HeadsetPreset) else get_preset(preset)
        self.refresh_hz = float(refresh_hz or self.preset.default_refresh)
        self.ipd = self.preset.ipd if ipd is None else float(ipd)
        self._size = tuple(int(s) for s in (size or self.preset.eye_size))
        if len(self._size) != 2 or min(self._size) <= 0:
            raise OptionError(f"SimulatedHeadset: size must be (width, height) in pixels, got {size!r}")
        self.start_pose = start_pose or DEFAULT_START
        self._start_pose_given = start_pose is not None
        self._trajectory_spec = trajectory
        self.trajectory = make_trajectory(trajectory, self.start_pose)
        self.gaze = make_gaze(gaze)
        self.frames = frames
        self.near, self.far, self.reversed_z = near, far, reversed_z
        self.frame_time_s = frame_time_s
        self.compositor = Compositor(self.refresh_hz, late_policy, max_late_vsyncs)
        self.record_dir = Path(record_dir) if record_dir is not None else None
        self.record_every = max(1, int(record_every))
        self.encode_srgb = encode_srgb
        self.video = _video_format(video)
        self.video_path: Path | None = None
        self._video_writer = None
        self._last_views = None
        self.gpu = None

    @property
    def start_pose_given(self) -> bool:
        """Whether a start pose was given (else the Renderer places the headset at the scene's camera)."""
        return self._start_pose_given

    def place(self, start_pose: Pose) -> None:
        """Start the (formula) trajectory from `start_pose`, e.g. the scene's camera; a pose log keeps its poses."""
        self.start_pose, self._start_pose_given = start_pose, True
        self.trajectory = make_trajectory(self._trajectory_spec, start_pose)

    @property
    def view_count(self) -> int:
        return 2

    @property
    def size(self) -> tuple[int, int]:
        return self._size

    def open(self, gpu) -> None:
        self.gpu = gpu
        if self.record_dir is not None:
            self.record_dir.mkdir(parents=True, exist_ok=True)

    def wait_frame(self) -> FrameRequest | None:
        if self.frames is not None and len(self.compositor.frames) >= self.frames:
            return None
        timing = self.compositor.begin_frame()
        head = self.trajectory.pose_at(timing.predicted_display_time)
        views = stereo_views(head, self.ipd, self.preset.left_fov, self.preset.right_fov, self._size,
                             self.near, self.far, self.reversed_z)
        views = ViewSet(views.views, previous=self._last_views)   # motion vectors: last frame's matrices
        if self.gaze is not None:
            views.gaze = gaze_tangents(views, head.rotation_matrix(), self.gaze.direction_at(timing.predicted_display_time))
        self._last_views = views
        return FrameRequest(timing.index, views, timing.predicted_display_time, head,
                            sink_data={"timing": timing, "wall_start": time.perf_counter()})

    def submit(self, texture_array, request: FrameRequest) -> None:
        timing = request.sink_data.get("timing")
        if timing is None or timing.status != "pending":
            raise XrError(f"SimulatedHeadset.submit(): frame {request.index} was not issued by this headset's "
                          f"wait_frame() or was already submitted; submit each request once")
        if request.render_time_s is not None:
            render_time = request.render_time_s
        elif self.frame_time_s is not None:
            render_time = self.frame_time_s
        else:
            render_time = time.perf_counter() - request.sink_data["wall_start"]
        self.compositor.end_frame(timing, render_time)
        if texture_array is not None:
            check_texture_array(texture_array, self, "SimulatedHeadset")
            if self.record_dir is not None and request.index % self.record_every == 0:
                self._record(texture_array, request.index)

    def _record(self, texture_array, index: int) -> None:
        from ..fileio import atomic_group, write_png
        from .readback import read_layers, side_by_side

        eyes = read_layers(texture_array, self.encode_srgb)
        with atomic_group():   # a frame's three files appear together
            for name, img in zip(("left", "right"), eyes):
                write_png(self.record_dir / f"frame_{index:05d}_{name}.png", img, alpha=True)
            sbs = side_by_side(eyes)
            write_png(self.record_dir / f"frame_{index:05d}_sbs.png", sbs, alpha=True)
        if self.video:
            if self._video_writer is None:
                import imageio.v2 as imageio

                self.video_path = self.record_dir / f"headset.{self.video}"
                kwargs = {"fps": self.refresh_hz} if self.video == "mp4" else {"duration": 1000 / self.refresh_hz}
                self._video_writer = imageio.get_writer(self.video_path, mode="I", **kwargs)
            self._video_writer.append_data(sbs[..., :3])

    def close(self) -> None:
        if self._video_writer is not None:
            self._video_writer.close()
            self._video_writer = None

    def stats(self) -> dict:
        """The compositor's counts and latency distributions (see rayvr.xr.compositor)."""
        return {"preset": self.preset.name, "eye_size": list(self._size), **self.compositor.stats()}


def _video_format(video) -> str | None:
    if not video:
        return None
    if video is True:
        try:
            import imageio_ffmpeg  # noqa: F401
            return "mp4"
        except ImportError:
            return "gif"
    if video not in ("mp4", "gif"):
        raise OptionError(f"SimulatedHeadset: video='{video}' is unknown; use True, 'mp4' or 'gif'")
    if video == "mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise OptionError("SimulatedHeadset: video='mp4' needs imageio-ffmpeg "
                              "('pip install imageio-ffmpeg'); or use video='gif'") from None
    return video
