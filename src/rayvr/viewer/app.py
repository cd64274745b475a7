"""The viewer's frame loop: input, camera, render, display, UI, screenshots, in that order.

    rv.view(rv.scenes.cornell_box(), rv.graphs.hybrid())     # a window until it is closed

A frame: poll the window (its callbacks and the script's events for this frame go through the
same InputState and ImGui), apply what changed at the frame boundary (a new view size or count
makes a new Renderer; an edited pass property recompiles the graph), move the camera, render the
views with the Renderer into the window's own GL context, draw the output texture array into the
window, draw the UI on top, take the screenshots asked for, call `on_frame`, present.
The scene and graph are the caller's objects: effects and pass properties edited in the viewer
stay in them.
"""
from __future__ import annotations

import collections
import contextlib
import time
from pathlib import Path

import numpy as np

from ..errors import OptionError, RayvrError, ViewerError
from ..gpu.context import use_context
from .camera import CameraRig
from ..tune.budget import FRAME_BUDGET_MS
from .display import FrameDisplay
from .input import InputEvent, InputState
from .script import InputScript
from .view_rig import ViewRig

BUDGET_MS = FRAME_BUDGET_MS   # 90 Hz
# Frames of a still view's running mean after which the summary calls it converged: its noise is
# a sixteenth of one frame's (1 / sqrt(256)), below what an 8-bit display shows of most scenes.
CONVERGED_FRAMES = 256
HISTORY = 240             # frames of timing kept for the plots
MAX_WINDOW = (1600, 900)  # the default window's largest size


def resolve_graph(spec):
    """A RenderGraph from a graph, None (hybrid), a ready-made graph's name ('hybrid',
    'path_traced': rayvr.graphs.COMMAND_LINE_GRAPHS), or a .json/.py file."""
    from ..graphs import BUILDERS, COMMAND_LINE_GRAPHS
    from ..rendergraph.graph import RenderGraph

    if isinstance(spec, RenderGraph):
        return spec
    if spec is None or spec in COMMAND_LINE_GRAPHS:
        return BUILDERS[spec or "hybrid"].build()
    path = Path(str(spec))
    if path.suffix.lower() in (".json", ".py"):
        return RenderGraph.load(path)
    raise OptionError(f"--graph {spec}: use {' or '.join(COMMAND_LINE_GRAPHS)}, or a saved graph (.json, .py)")


def builder_name(spec) -> str | None:
    """The ready-made graph `spec` names (None: 'hybrid'), or None for a given or saved graph."""
    from ..graphs import COMMAND_LINE_GRAPHS

    if spec is None:
        return "hybrid"
    return spec if isinstance(spec, str) and spec in COMMAND_LINE_GRAPHS else None


def resolve_scene(spec):
    """A Scene, or one from a built-in name or glTF path (None: the Cornell box)."""
    from ..scene.spec import load_scene_spec

    if spec is None or isinstance(spec, (str, Path)):
        return load_scene_spec(None if spec is None else str(spec))
    return spec


class Viewer:
    """A live view of `scene` through `graph` (see the module docstring).

    views: 1 or 2; size: per-view pixels; preset: a headset preset name (rayvr.xr.presets) whose
    per-eye fov and IPD to use, at its panel size times `preset_scale`; surface: a Window (the
    default, `window_size` pixels, else the views side by side) or an OffscreenSurface; script:
    an InputScript (or a path); dt: seconds per frame of simulated time (default: the script's,
    else wall time); on_frame(viewer): called after each frame is drawn, before it is shown
    (changes apply to the next frame; return False to stop).
    """

    def __init__(self, scene, graph=None, views: int = 2, size=(512, 512), preset: str | None = None,
                 preset_scale: float = 1.0, surface=None, window_size=None, show_ui: bool = True,
                 script=None, dt: float | None = None, on_frame=None, ipd: float | None = None):
        self.scene = resolve_scene(scene)
        self.graph = resolve_graph(graph)
        self.graph_builder = builder_name(graph)   # rayvr.graphs.BUILDERS' name, when opened by one
        self.graph_options: dict = {}              # its options set in the viewer (rayvr.graph_options)
        self.rig = ViewRig.from_scene(self.scene, views, size, ipd=ipd)
        self.preset_scale = float(preset_scale)   # a preset's panel size times this
        if preset:
            self.rig = self.rig.with_preset(preset, self.preset_scale)
        lo, hi = np.asarray(self.scene.bounds(), dtype=np.float64)
        self.extent = max(float(np.linalg.norm(hi - lo)), 1e-3)
        from ..xr.cameras import camera_pose

        self.camera = CameraRig(camera_pose(self.scene)[0], 0.5 * (lo + hi), speed=0.5 * self.extent)
        self.input = InputState()
        self.script: InputScript | None = script if isinstance(script, InputScript) else None
        self.dt = dt
        self.on_frame = on_frame
        self.ui = self.renderer = None
        self._show_ui = bool(show_ui)
        self.display_mode = "side_by_side"
        self.error_overlay = None   # hook: callable(viewer) -> texture array like the output, or None
        self.overlay_alpha = 0.5
        self.target_frames = 0      # stop rendering once this many frames accumulated (0: never)
        self.target_seconds = 0.0   # ... or once this long since the view last changed (0: never)
        self.status, self.status_is_error = "", False
        self.recording = None       # a rayvr.xr.CameraPath while recording
        self.frame_index = 0
        self.camera_index = 0       # the scene camera last chosen
        self.time = 0.0             # simulated seconds (dt per frame) or wall seconds
        self.phase_ms = {"render": 0.0, "display": 0.0, "ui": 0.0}
        self.sync_phases = False    # finish the GPU after each phase so phase_ms includes its work
        self.history: dict[str, collections.deque] = {}   # pass -> its last frames' ms, and "total"
        self._history_compiles = None
        self.profile = None         # the renderer's profile after the last frame rendered
        self.frame_ms = collections.deque(maxlen=HISTORY)
        self.rendered = False       # whether the last frame rendered (False: converged, shown again)
        self.rendered_once = False  # whether this view and scene state has rendered at all
        self._quit = False
        self._screenshots: list[tuple[str, bool]] = []
        self._pending_rebuild = self._pending_recompile = False
        self._last_views = self._view_key = self._last_wall = None
        self._accum_started = time.perf_counter()
        self._stack = contextlib.ExitStack()
        try:
            self._open(surface, window_size, script)
        except BaseException:
            self._stack.close()   # the window closes, a stepped-aside context returns
            raise

    def _open(self, surface, window_size, script) -> None:
        """The window (or the given surface), its context as the default, the renderer, the UI."""
        from .panels import Panels
        from .ui import Ui

        if surface is None:
            from .window import Window

            surface = Window(window_size or default_window_size(self.rig), title=f"rayvr: {self.scene.name}")
        self._stack.callback(surface.close)
        self.surface, self.gpu = surface, surface.gpu
        self._stack.enter_context(use_context(self.gpu))   # get_context() answers the window's context
        surface.on_event = self.handle_event
        if isinstance(script, (str, Path)):
            self.script = InputScript.load(script, surface.key_names)
        if self.dt is None and self.script is not None:
            self.dt = self.script.dt
        self.display = FrameDisplay(self.gpu.gl)
        self._stack.callback(self.display.release)
        self._stack.callback(self._close_renderer)
        self._make_renderer()
        self.ui = Ui()
        self._stack.callback(self.ui.close)
        self.panels = Panels(self)

    @property
    def show_ui(self) -> bool:
        """Whether the panels are drawn (and get input)."""
        return self._show_ui

    @show_ui.setter
    def show_ui(self, on: bool) -> None:
        if on and not self._show_ui and self.ui is not None:
            self.ui.resume(self.input)   # it got no input while hidden
        self._show_ui = bool(on)

    # -- renderer ---------------------------------------------------------------------------------
    def _make_renderer(self) -> None:
        from ..renderer import Renderer

        self._close_renderer()
        self._last_views = None
        self.renderer = Renderer(self.scene, self.graph, views=self.rig.view_set(self.camera.pose), gpu=self.gpu)
        self.profile = self.renderer.profile()
        self.history.clear()
        self.frame_ms.clear()

    def _close_renderer(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None

    def _apply_pending(self) -> None:
        if self._pending_rebuild:
            self._pending_rebuild = self._pending_recompile = False
            self._make_renderer()
        elif self._pending_recompile:
            self._pending_recompile = False
            self.renderer.recompile()

    # -- what the panels and scripts change (applied at the next frame boundary) ------------------
    def set_rig(self, rig: ViewRig) -> None:
        """New views: a new size or view count makes a new Renderer before the next frame."""
        if (rig.views, rig.size) != (self.rig.views, self.rig.size):
            self._pending_rebuild = True
        self.rig = rig

    def set_preset(self, name: str | None, scale: float | None = None) -> None:
        """A headset preset's per-eye fov, IPD and panel size times `scale` (default
        `preset_scale`); None: the scene's camera at the current size."""
        if scale is not None:
            self.preset_scale = float(scale)
        if name is None:
            self.set_rig(ViewRig.from_scene(self.scene, self.rig.views, self.rig.size, ipd=self.rig.ipd))
        else:
            self.set_rig(self.rig.with_preset(name, self.preset_scale))

    def set_pass_property(self, pass_name: str, key: str, value) -> None:
        """Set one property of a pass (graph.update_pass); the graph recompiles before the next frame."""
        self.graph.update_pass(pass_name, {key: value})
        self._pending_recompile = True

    def set_graph_option(self, option: str, value) -> None:
        """Build the ready-made graph again with `option` = `value` (rayvr.graph_options; None or
        'none': off) and the options set before; a new Renderer compiles it before the next frame
        (pass properties edited since go with the old graph). A graph given or loaded has none."""
        from ..graph_options import NONE
        from ..graphs import BUILDERS

        if self.graph_builder is None:
            raise OptionError(f"graph option {option}: graph '{self.graph.name}' was given or loaded, not built by "
                              f"name; edit its passes' properties instead")
        builder = BUILDERS[self.graph_builder]
        if not builder.takes(option):
            raise OptionError(f"graph option {option}: {builder.name} takes "
                              f"{', '.join(o.name for o in builder.options)}")
        # an option turned off is passed as None: the builder's preset may turn it on otherwise
        options = {k: (None if v == NONE else v) for k, v in {**self.graph_options, option: value}.items()}
        self.graph = builder.build(**options)
        self.graph_options = options
        self._pending_rebuild = True

    def set_effect(self, material: str, effect) -> None:
        """Change a material's effect (the Renderer recompiles when the set of effects changes)."""
        from .assignment import apply_assignment

        apply_assignment(self.scene, {material: effect})

    def apply_assignment_file(self, path) -> dict:
        """Apply {material: effect} from a JSON file or a rayvr tune result; returns it."""
        from .assignment import apply_assignment, load_assignment

        assignment = load_assignment(path, self.scene)
        apply_assignment(self.scene, assignment)
        return assignment

    def use_scene_camera(self, index: int) -> None:
        """Stand at the scene's camera `index`, with its vertical fov."""
        from ..xr import quaternion
        from ..xr.views import Pose

        cam = self.scene.cameras[index]
        m = np.asarray(cam.transform, dtype=np.float64)
        rot = m[:3, :3] / np.linalg.norm(m[:3, :3], axis=0)
        self.camera_index = index
        self.camera.set_pose(Pose(m[:3, 3].copy(), quaternion.from_matrix(rot)))
        self.set_rig(self.rig.with_vertical_fov(float(np.degrees(cam.yfov))))

    def quit(self) -> None:
        """Stop after this frame."""
        self._quit = True

    # -- output -------------------------------------------------------------------------------------
    def request_screenshot(self, path, strict: bool = True) -> None:
        """Write the window (frame and UI) as PNG, or the HDR output as EXR, after this frame draws.
        A failure raises (strict) or shows in the status line (a UI button's request)."""
        self._screenshots.append((str(path), strict))

    def read_window(self) -> np.ndarray:
        """The window's pixels as drawn so far this frame, (h, w, 3) uint8, rows top-down."""
        from .screenshot import read_framebuffer

        return read_framebuffer(self.surface.framebuffer, self.surface.framebuffer_size)

    def _take_screenshots(self) -> None:
        from .screenshot import save_hdr, save_png

        pixels = None
        requests, self._screenshots = self._screenshots, []
        for path, strict in requests:
            try:
                if path.lower().endswith(".exr"):
                    save_hdr(path, self.renderer)
                else:
                    pixels = self.read_window() if pixels is None else pixels
                    save_png(path, pixels)
            except RayvrError as exc:
                if strict:
                    raise
                self.say(" ".join(str(exc).split()), error=True)
                continue
            self.say(f"wrote {path}")

    def save_graph(self, path) -> Path:
        """Write the current graph (with its edited properties) as .py or .json."""
        if Path(path).suffix.lower() not in (".py", ".json"):
            raise OptionError(f"{path}: save the graph as .py (a script) or .json")
        return self.graph.save(path)

    def save_effects(self, path) -> Path:
        """Write the materials' effects as JSON {material: effect}."""
        from .assignment import save_assignment

        return save_assignment(path, self.scene)

    def start_recording(self) -> None:
        """Record the head pose of every frame from now (save with `save_camera_path`)."""
        from ..xr.camera_path import CameraPath

        self.recording = CameraPath(ipd=self.rig.ipd, fov_left=self.rig.fov_left, fov_right=self.rig.fov_right,
                                    near=self.rig.near, far=self.rig.far)

    def save_camera_path(self, path) -> Path:
        """Write the recorded path (the poses so far) as JSON for `rayvr render --camera-path`."""
        if self.recording is None:
            raise OptionError(f"{path}: nothing recorded; start recording first")
        return self.recording.save(path)

    def say(self, text: str, error: bool = False) -> None:
        """Show `text` in the status line."""
        self.status, self.status_is_error = text, error

    # -- accumulation ----------------------------------------------------------------------------------
    def accumulated(self) -> tuple[int, float]:
        """(frames in the running mean, seconds since it restarted): the most of the enabled
        Accumulate passes' counts and TAA's still frames, else frames since the view last changed."""
        from ..passes.accumulate import Accumulate

        from ..passes.taa import TAA

        passes = self.renderer.compiled.passes.values()
        counts = [p.frame_count for p in passes if isinstance(p, Accumulate) and p.enabled]
        counts += [p.still_frames for p in passes if isinstance(p, TAA)]   # a still view's exact mean
        frames = max(counts) if counts else self.renderer.sample_index + 1
        return frames, time.perf_counter() - self._accum_started

    def converged(self) -> bool:
        """True when a target sample count or time is set and reached since the views or the
        scene last changed: rendering pauses and the last frame stays on screen."""
        if not (self.target_frames or self.target_seconds) or not self.rendered_once:
            return False
        frames, seconds = self.accumulated()
        return bool((self.target_frames and frames >= self.target_frames)
                    or (self.target_seconds and seconds >= self.target_seconds))

    def settled(self) -> bool:
        """Whether the view counts as converged: rendering paused at a target, or a still view's
        running mean has CONVERGED_FRAMES frames."""
        return (self.rendered_once and not self.rendered) or self.accumulated()[0] >= CONVERGED_FRAMES

    # -- input ---------------------------------------------------------------------------------------
    def handle_event(self, event: InputEvent) -> None:
        """One input event, from the window or the script: to ImGui, then to the camera's state."""
        if self.show_ui:   # hidden panels get no input: ImGui would queue it for when they show
            self.ui.feed(event)
        self.input.handle(event)

    def _shortcuts(self) -> None:
        pressed = self.input.pressed
        if not pressed:
            return
        if "H" in pressed or "F1" in pressed:
            self.show_ui = not self.show_ui
        if "R" in pressed:
            self.camera.reset()
        if "F" in pressed:
            self.camera.set_mode("fly")
        if "O" in pressed:
            self.camera.set_mode("orbit")
        if "C" in pressed and self.scene.cameras:
            self.use_scene_camera((self.camera_index + 1) % len(self.scene.cameras))
        if "TAB" in pressed and self.rig.views == 2:
            from .display import MODES

            self.display_mode = MODES[(MODES.index(self.display_mode) + 1) % len(MODES)]
        if "F12" in pressed:
            self.request_screenshot(f"out/view_{self.frame_index:05d}.png", strict=False)
        if "ESCAPE" in pressed:
            self.quit()

    def _play_script(self) -> None:
        if self.script is None:
            return
        for item in self.script.at(self.frame_index):
            if isinstance(item, InputEvent):
                self.handle_event(item)
            elif item.kind == "effect":
                for material, effect in item.value.items():
                    self.set_effect(material, effect)
            elif item.kind == "screenshot":
                self.request_screenshot(item.value)
            elif item.kind == "quit":
                self.quit()

    # -- the frame -------------------------------------------------------------------------------------
    def _tick(self) -> float:
        now = time.perf_counter()
        if self.dt is not None:
            dt = self.dt
        else:
            dt = 0.0 if self._last_wall is None else min(now - self._last_wall, 0.25)
        self._last_wall = now
        self.time += dt
        return dt

    def _timed(self, phase: str, fn, *args):
        t0 = time.perf_counter()
        out = fn(*args)
        if self.sync_phases:
            self.gpu.gl.finish()
        self.phase_ms[phase] = (time.perf_counter() - t0) * 1e3
        return out

    def step(self) -> None:
        """Draw one frame (see the module docstring)."""
        t0 = time.perf_counter()
        dt = self._tick()
        self.input.begin_frame()
        if self.show_ui:
            self.ui.share_wants(self.input)
        else:
            self.input.ui_wants_mouse = self.input.ui_wants_keyboard = False
        self.surface.poll()
        self._play_script()
        self._shortcuts()
        self._apply_pending()
        self.camera.update(self.input, dt)
        views = self.rig.view_set(self.camera.pose, previous=self._last_views)
        if self.recording is not None:
            self.recording.append(self.time, self.camera.pose)
        # What restarts accumulation: the views, the materials, a recompile or a new renderer.
        key = (_view_key(views), self.scene.materials.version, id(self.renderer), self.renderer.compiles)
        if key != self._view_key:
            self._view_key = key
            self._accum_started = time.perf_counter()
            self.rendered_once = False
        self.rendered = not self.converged()
        if self.rendered:
            self._timed("render", self.renderer.render, views)
            self.rendered_once = True
            self._record_times()
            if self.renderer.sample_index == 0:
                self._accum_started = time.perf_counter()
        self._last_views = views
        fb_size = self.surface.framebuffer_size
        self._timed("display", self.display.draw, self.surface.framebuffer, fb_size, self.renderer.output_texture(),
                    self.renderer.view_count, self.renderer.size, self.display_mode,
                    self.error_overlay(self) if self.error_overlay else None, self.overlay_alpha)
        if self.show_ui:
            self._timed("ui", self.ui.frame, self.surface.window_size, fb_size, max(dt, 1e-3), self.panels.draw)
        else:
            self.phase_ms["ui"] = 0.0
        self._take_screenshots()
        if self.on_frame is not None and self.on_frame(self) is False:
            self.quit()
        self.surface.present()
        self.frame_ms.append((time.perf_counter() - t0) * 1e3)
        self.frame_index += 1

    def _record_times(self) -> None:
        """Keep this frame's profile (the panels read it) and each pass's time for the plots; a
        recompile (new effects, an edited property) starts the plots again."""
        self.profile = profile = self.renderer.profile()
        if self.renderer.compiles != self._history_compiles:
            self.history.clear()
            self._history_compiles = self.renderer.compiles
        total = 0.0
        for name, stats in profile.passes.items():
            self.history.setdefault(name, collections.deque(maxlen=HISTORY)).append(stats.last_ms)
            total += stats.last_ms
        self.history.setdefault("total", collections.deque(maxlen=HISTORY)).append(total)

    def run(self, frames: int | None = None, screenshot=None) -> int:
        """Draw frames until the window closes, `quit()`, the script quits, or `frames` are drawn;
        `screenshot` (needs `frames`): the window (.png) or HDR output (.exr) as the last frame
        draws. Returns the count drawn."""
        if screenshot is not None and frames is None:
            raise OptionError(f"screenshot {screenshot}: needs a frame count (the frame to write); "
                              f"a script can take screenshots at any frame")
        if frames is not None and frames < 1:
            raise OptionError(f"frames {frames}: draw at least 1 frame")
        count = 0
        while (frames is None or count < frames) and not self._quit and not self.surface.should_close():
            if screenshot is not None and count == frames - 1:
                self.request_screenshot(screenshot)
            self.step()
            count += 1
        if screenshot is not None and count < frames:
            raise ViewerError(f"{screenshot}: not written: the viewer stopped after {count} of {frames} frames")
        return count

    def close(self) -> None:
        """Free the renderer, the UI and the window (the caller's scene and graph stay)."""
        self._stack.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def default_window_size(rig: ViewRig) -> tuple[int, int]:
    """The views side by side, shrunk to fit MAX_WINDOW (a headset's panels are large)."""
    w, h = rig.size[0] * rig.views, rig.size[1]
    scale = min(1.0, MAX_WINDOW[0] / w, MAX_WINDOW[1] / h)
    return max(1, round(w * scale)), max(1, round(h * scale))


def _view_key(views) -> bytes:
    """What identifies the views' geometry this frame (accumulation restarts when it changes)."""
    return b"".join(np.concatenate([v.pose.position, v.pose.orientation, v.fov.tangents(),
                                    (v.width, v.height)]).tobytes() for v in views)


def view(scene=None, graph=None, views: int = 2, size=(512, 512), frames: int | None = None,
         screenshot=None, script=None, on_frame=None, preset: str | None = None, preset_scale: float = 1.0,
         show_ui: bool = True, window_size=None) -> int:
    """Open a window on `scene` (a Scene, a built-in name or a glTF path; None: the Cornell box)
    rendered by `graph` (a RenderGraph, 'hybrid', 'path_traced' or a saved .json/.py; None:
    hybrid) until it is closed, or for `frames` frames; `screenshot`: a .png of the window (or .exr
    of the HDR output) written after the last frame. Returns the frames drawn.
    RayvrError (ViewerError) when there is no display or the viewer extra is missing."""
    from .deps import require_window_support

    require_window_support()
    if screenshot is not None and frames is None:
        raise OptionError(f"screenshot {screenshot}: needs frames=N (the frame to write)")
    with Viewer(scene, graph, views=views, size=size, preset=preset, preset_scale=preset_scale, show_ui=show_ui,
                script=script, on_frame=on_frame, window_size=window_size) as viewer:
        return viewer.run(frames, screenshot)


__all__ = ["Viewer", "view", "resolve_graph", "resolve_scene", "BUDGET_MS"]
