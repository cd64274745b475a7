"""`OpenXRSink`: frames to a real headset through an OpenXR runtime (SteamVR, Monado), via pyopenxr.

pyopenxr (import name `xr`) is imported here, on `open()`, and nowhere else in rayvr.

The sequence follows the OpenXR 1.0 specification:
instance (XR_KHR_opengl_enable, plus XR_MNDX_egl_enable on an EGL context; optionally
XR_KHR_composition_layer_depth) -> system (HEAD_MOUNTED_DISPLAY) -> view configuration views
(PRIMARY_STEREO) -> xrGetOpenGLGraphicsRequirementsKHR (mandatory before xrCreateSession) ->
session with the EGL or Xlib graphics binding -> reference space (STAGE if offered, else LOCAL) ->
swapchains (one array swapchain with a layer per view, else one per view) -> the frame loop:
xrPollEvent (session lifecycle, see openxr_lifecycle.py), xrWaitFrame, xrBeginFrame,
xrLocateViews, [render], acquire/wait/copy/release swapchain images, xrEndFrame with one
projection layer whose views carry the located pose and fov. Where the runtime offers
XR_EXT_eye_gaze_interaction and its system supports it, the sink enables it and each frame's
views carry the eye gaze at the frame's display time (`ViewSet.gaze`; openxr_gaze.py), which
foveation 'gaze' follows.

The frame the sink is in the middle of is tracked (`frame_phase`: waiting, waited, begun): a
frame that was waited but not begun (Ctrl-C inside xrWaitFrame, or an error between the calls)
is begun and ended with no layers before any further xrWaitFrame and in close(), because the
specification lets the next xrWaitFrame block until the previous frame is begun. Runtime errors
anywhere in the session, the frame loop included, reach the caller as XrError naming the step.
"""
from __future__ import annotations

import contextlib
import ctypes
import os
import time

from ..errors import XrError
from .gaze import direction_tangents
from .openxr_convert import projection_views, version_tuple, views_from_located
from .openxr_gaze import EyeGaze, system_supports
from .openxr_gl import (COLOR_PREFERENCE, DEPTH_PREFERENCE, GL_TEXTURE_2D, GL_TEXTURE_2D_ARRAY, GLPlatform,
                        SwapchainCopier, choose_format)
from .openxr_lifecycle import Action, SessionLifecycle, SessionState
from .sink import FrameRequest, Sink, check_texture_array
from .views import Pose

NO_RUNTIME = ("no OpenXR runtime: install SteamVR or Monado and make it the active runtime (set XR_RUNTIME_JSON "
              "to its manifest, e.g. XR_RUNTIME_JSON=<monado build>/openxr_monado-dev.json, or install "
              "/etc/xdg/openxr/1/active_runtime.json), or use SimulatedHeadset")
VALIDATION_LAYER = "XR_APILAYER_LUNARG_core_validation"


def import_pyopenxr():
    """The pyopenxr module (`xr`), or an XrError saying how to install it."""
    try:
        import xr
    except ImportError as exc:
        raise XrError(f"OpenXRSink needs pyopenxr ('pip install pyopenxr'): {exc}; "
                      f"or use SimulatedHeadset") from exc
    return xr


class _Swapchain:
    """One XrSwapchain, its GL image names, and which views it holds."""

    def __init__(self, handle, images: list[int], array: bool, first_view: int, view_count: int):
        self.handle, self.images, self.array = handle, images, array
        self.first_view, self.view_count = first_view, view_count


class OpenXRSink(Sink):
    """A stereo headset through the OpenXR runtime of this machine.

    reference_space: "stage" (floor-level, falls back to "local") or "local".
    world_pose: where the reference space sits in the scene (a Pose; default identity).
    depth: also submit depth (XR_KHR_composition_layer_depth) when the runtime has it; pass
    `depth_array=` (same internal format as the depth swapchain) to every rendered submit().
    rv.Renderer submits colour only (its graphs have no depth output): with depth=True a rendered
    frame submitted without depth_array is refused with an XrError rather than silently sent
    without depth, so drive such a sink yourself or leave depth off.
    source_srgb: whether submitted colour is sRGB-encoded (default: yes for rgba8, no for floats).
    validation: enable the Khronos core validation layer (if installed with pyopenxr).
    frames: request exit after this many frames (None: until the runtime ends the session).
    eye_gaze: enable XR_EXT_eye_gaze_interaction where the runtime and system offer it (`gaze`
    is then the session's EyeGaze, else None).
    api: the pyopenxr module or a stand-in (tests); default `import xr`.
    """

    def __init__(self, app_name: str = "rayvr", reference_space: str = "stage", world_pose: Pose | None = None,
                 near: float = 0.05, far: float = 1000.0, reversed_z: bool = False, depth: bool = False,
                 source_srgb: bool | None = None, array_swapchain: bool = True, validation: bool = False,
                 frames: int | None = None, recover: bool = True, recover_timeout_s: float = 5.0,
                 exit_timeout_s: float = 3.0, eye_gaze: bool = True, api=None):
        if reference_space not in ("stage", "local"):
            raise XrError(f"OpenXRSink: reference_space '{reference_space}' is unknown; use 'stage' or 'local'")
        self.app_name, self.reference_space = app_name, reference_space
        self.world_pose = world_pose
        self.near, self.far, self.reversed_z = near, far, reversed_z
        self.want_depth, self.source_srgb = depth, source_srgb
        self.want_array = array_swapchain
        self.validation, self.frames = validation, frames
        self.recover, self.recover_timeout_s, self.exit_timeout_s = recover, recover_timeout_s, exit_timeout_s
        self.xr = api
        self.want_gaze = bool(eye_gaze)
        self.gaze = None
        self.instance = self.system = self.session = self.space = None
        self.swapchains: list[_Swapchain] = []
        self.depth_swapchains: list[_Swapchain] = []
        self.lifecycle = SessionLifecycle()
        self.frame_count = 0
        self.extensions: list[str] = []
        self.color_format = self.depth_format = None
        self._size = None
        self._view_count = None
        self._previous_views = None
        self._instance_lost = False
        self.frame_phase = None      # None, "waiting", "waited" (not begun) or "begun" (not ended)
        self._display_time = None    # the XrTime of the frame in flight (or of the last one)
        self._display_period = 0

    # -- Sink -------------------------------------------------------------------------------

    @property
    def view_count(self) -> int:
        """The runtime's PRIMARY_STEREO view count (asks the runtime on first use)."""
        self._ensure_system()
        return self._view_count

    @property
    def size(self) -> tuple[int, int]:
        """The runtime's recommended per-view size (asks the runtime on first use)."""
        self._ensure_system()
        return self._size

    def open(self, gpu) -> None:
        self.gl = gpu.gl
        self.gl_version = int(getattr(gpu.caps, "gl_version", 450))
        self._ensure_system()
        with self._runtime_errors("creating the session and swapchains"):
            self._create_session()

    @contextlib.contextmanager
    def _runtime_errors(self, step: str):
        """Turn a pyopenxr exception (an error result, or a success code nobody expected) into an
        XrError naming the step; KeyboardInterrupt and rayvr's own errors pass through."""
        try:
            yield
        except XrError:
            raise
        except Exception as exc:
            if self.xr is not None and isinstance(exc, self.xr.exception.XrException):
                raise XrError(f"OpenXR runtime failed while {step}: {exc} ({type(exc).__name__}); "
                              f"see the runtime's log, or use SimulatedHeadset") from exc
            raise

    def _ensure_system(self) -> None:
        """Instance, system and view configuration: what view_count and size need (no session yet).

        Needs the GL context current (rayvr.gpu.get_context()), to choose the EGL or GLX binding."""
        if self._size is not None:
            return
        xr = self.xr = self.xr or import_pyopenxr()
        self.platform = GLPlatform()
        with self._runtime_errors("creating the instance and system"):
            if self.instance is None:
                self._create_instance()
            self._get_system()
        views = xr.enumerate_view_configuration_views(self.instance, self.system, xr.ViewConfigurationType.PRIMARY_STEREO)
        self._view_count = len(views)
        self._size = (max(v.recommended_image_rect_width for v in views),
                      max(v.recommended_image_rect_height for v in views))
        modes = list(xr.enumerate_environment_blend_modes(self.instance, self.system,
                                                          xr.ViewConfigurationType.PRIMARY_STEREO))
        self.blend_mode = xr.EnvironmentBlendMode.OPAQUE if xr.EnvironmentBlendMode.OPAQUE in modes else modes[0]

    def wait_frame(self) -> FrameRequest | None:
        with self._runtime_errors("waiting for the next frame"):
            return self._wait_frame()

    def _wait_frame(self) -> FrameRequest | None:
        xr = self.xr
        deadline = None
        while True:
            self._poll_events()
            if self._instance_lost:
                return None
            if self.lifecycle.state == SessionState.EXITING:
                return None
            if self.lifecycle.state == SessionState.LOSS_PENDING:
                if not (self.recover and self._recover_session()):
                    return None
                continue
            if self.frames is not None and self.frame_count >= self.frames and not self.lifecycle.exit_requested:
                self.request_exit()
            if self.lifecycle.should_request_exit():
                xr.request_exit_session(self.session)
                self.lifecycle.exit_sent = True
            if self.lifecycle.running:
                return self._begin_frame()
            if self.lifecycle.exit_requested and self.lifecycle.state in (SessionState.IDLE, SessionState.UNKNOWN):
                # exit asked before the session ever ran (or after it ended): nothing more will come
                deadline = deadline or time.monotonic() + self.exit_timeout_s
                if time.monotonic() > deadline:
                    return None
            time.sleep(0.002)   # IDLE: wait for the runtime's READY (or EXITING)

    def submit(self, texture_array, request: FrameRequest, depth_array=None) -> None:
        located = request.sink_data.get("located")
        if located is None or request.sink_data.get("ended"):
            raise XrError(f"OpenXRSink.submit(): frame {request.index} was not begun by this sink's wait_frame() "
                          f"or was already submitted; submit each request once")
        if self.depth_swapchains and request.should_render and texture_array is not None and depth_array is None:
            raise XrError(f"OpenXRSink(depth=True): frame {request.index} was submitted without depth_array; pass "
                          f"the frame's depth (a {self.depth_format and hex(self.depth_format)} texture array) or "
                          f"create the sink with depth=False (rv.Renderer has no depth output to submit)")
        request.sink_data["ended"] = True
        with self._runtime_errors(f"submitting frame {request.index}"):
            self._submit(texture_array, request, located, depth_array)

    def _submit(self, texture_array, request: FrameRequest, located, depth_array) -> None:
        xr = self.xr
        layers = []   # the structs it points to are locals, alive until xrEndFrame returns
        if request.should_render and texture_array is not None:
            check_texture_array(texture_array, self, "OpenXRSink")
            source_srgb = self.source_srgb if self.source_srgb is not None else texture_array.dtype == "f1"
            targets = self._acquire(self.swapchains)
            self.copier.copy(texture_array, source_srgb, targets)
            self._release(self.swapchains)
            depth_infos = None
            if self.depth_swapchains and depth_array is not None:
                self.copier.copy_depth(depth_array, self._acquire(self.depth_swapchains))
                self._release(self.depth_swapchains)
                depth_infos = self._depth_infos
            views = projection_views(xr, located, self._sub_images, depth_infos)
            layer = xr.CompositionLayerProjection(space=self.space, views=views)
            layers = [ctypes.byref(layer)]
        xr.end_frame(self.session, xr.FrameEndInfo(display_time=request.sink_data["display_time"],
                                                   environment_blend_mode=self.blend_mode, layers=layers))
        self.frame_phase = None
        self.frame_count += 1

    def request_exit(self) -> None:
        """Ask the runtime to end the session cleanly (STOPPING -> IDLE -> EXITING follow)."""
        self.lifecycle.exit_requested = True

    def close(self) -> None:
        """End the session the way the lifecycle asks (request exit, run empty frames until
        STOPPING, end it), then destroy everything. A frame left in flight is settled first; a
        runtime that fails on the way out does not stop the release."""
        if self.xr is None or self.instance is None:
            return
        xr = self.xr
        self._settle_frame()
        if self.session is not None and self.lifecycle.running and not self._instance_lost:
            self.request_exit()
            deadline = time.monotonic() + self.exit_timeout_s
            try:
                while self.lifecycle.running and time.monotonic() < deadline:
                    request = self.wait_frame()
                    if request is None:
                        break
                    request.should_render = False
                    self.submit(None, request)
            except XrError:
                self._settle_frame()   # the runtime is failing: release what we hold all the same
        self._destroy_session()
        try:
            xr.destroy_instance(self.instance)
        except Exception:   # the instance may already be lost; nothing more to release
            pass
        self.instance = None
        restore_stdin()

    # -- setup ------------------------------------------------------------------------------

    def _create_instance(self) -> None:
        xr = self.xr
        try:
            available = {e.extension_name.decode() if isinstance(e.extension_name, bytes) else e.extension_name
                         for e in xr.enumerate_instance_extension_properties()}
        except xr.exception.RuntimeUnavailableError as exc:
            raise XrError(NO_RUNTIME) from exc
        except xr.exception.RuntimeFailureError as exc:
            raise XrError(f"{NO_RUNTIME} (the runtime failed to load: {exc})") from exc
        wanted = [xr.KHR_OPENGL_ENABLE_EXTENSION_NAME]
        if self.platform.kind == "egl":
            wanted.append(xr.MNDX_EGL_ENABLE_EXTENSION_NAME)
        missing = [e for e in wanted if e not in available]
        if missing:
            how = ("this runtime has no headless EGL binding; run Monado, or create rayvr's context through "
                   "GLX (RAYVR_GL_BACKEND=default with an X display) on a desktop") if self.platform.kind == "egl" else \
                  "this runtime cannot present OpenGL; use one that supports XR_KHR_opengl_enable"
            raise XrError(f"OpenXR runtime lacks {', '.join(missing)}: {how}")
        if self.want_depth and xr.KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME in available:
            wanted.append(xr.KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME)
        if self.want_gaze and xr.EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME in available:
            wanted.append(xr.EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME)
        layers = []
        if self.validation:
            expose = getattr(getattr(xr, "api_layer", None), "expose_packaged_api_layers", None)
            if expose is not None:
                expose()   # pyopenxr ships the Khronos layers: put them on XR_API_LAYER_PATH
            names = {p.layer_name.decode() if isinstance(p.layer_name, bytes) else p.layer_name
                     for p in xr.enumerate_api_layer_properties()}
            if VALIDATION_LAYER not in names:
                raise XrError(f"OpenXRSink(validation=True): the API layer {VALIDATION_LAYER} is not installed; "
                              f"set XR_API_LAYER_PATH to pyopenxr's api_layer folder or drop validation")
            layers.append(VALIDATION_LAYER)
        self.extensions = wanted
        info = xr.InstanceCreateInfo(
            application_info=xr.ApplicationInfo(application_name=self.app_name, engine_name="rayvr"),
            enabled_api_layer_names=layers, enabled_extension_names=wanted)
        try:
            self.instance = xr.create_instance(info)
        except xr.exception.RuntimeUnavailableError as exc:
            raise XrError(NO_RUNTIME) from exc

    def _get_system(self) -> None:
        xr = self.xr
        try:
            self.system = xr.get_system(self.instance, xr.SystemGetInfo(form_factor=xr.FormFactor.HEAD_MOUNTED_DISPLAY))
        except xr.exception.FormFactorUnavailableError as exc:
            raise XrError("OpenXR runtime found no headset (FORM_FACTOR_UNAVAILABLE): connect and switch on the "
                          "HMD, or use SimulatedHeadset") from exc

    def _create_session(self) -> None:
        xr = self.xr
        # Mandatory before xrCreateSession (XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING otherwise).
        reqs = xr.get_opengl_graphics_requirements_khr(self.instance, self.system)
        have = (self.gl_version // 100, (self.gl_version // 10) % 10)
        low = version_tuple(reqs.min_api_version_supported)[:2]
        if have < low:
            raise XrError(f"OpenXR runtime needs OpenGL {low[0]}.{low[1]}+, rayvr's context is {have[0]}.{have[1]}; "
                          f"update the GPU driver")
        binding = self.platform.egl_binding(xr) if self.platform.kind == "egl" else self.platform.xlib_binding(xr)
        self._binding = binding   # the struct must outlive xrCreateSession
        self.session = xr.create_session(self.instance, xr.SessionCreateInfo(system_id=self.system,
                                                                             next=binding))
        self.lifecycle = SessionLifecycle()
        spaces = list(xr.enumerate_reference_spaces(self.session))
        kind = xr.ReferenceSpaceType.STAGE if (self.reference_space == "stage"
                                               and xr.ReferenceSpaceType.STAGE in spaces) else xr.ReferenceSpaceType.LOCAL
        self.space_type = kind
        self.space = xr.create_reference_space(self.session, xr.ReferenceSpaceCreateInfo(
            reference_space_type=kind, pose_in_reference_space=xr.Posef()))
        self.gaze = None
        if xr.EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME in self.extensions and system_supports(xr, self.instance,
                                                                                              self.system):
            self.gaze = EyeGaze(xr, self.instance, self.session)
        formats = list(xr.enumerate_swapchain_formats(self.session))
        self.color_format = choose_format(formats, COLOR_PREFERENCE)
        usage = xr.SwapchainUsageFlags.COLOR_ATTACHMENT_BIT | xr.SwapchainUsageFlags.TRANSFER_DST_BIT
        self.swapchains = self._make_swapchains(self.color_format, usage)
        self.depth_swapchains = []
        if xr.KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME in self.extensions:
            self.depth_format = choose_format(formats, DEPTH_PREFERENCE)
            usage = xr.SwapchainUsageFlags.DEPTH_STENCIL_ATTACHMENT_BIT | xr.SwapchainUsageFlags.TRANSFER_DST_BIT
            self.depth_swapchains = self._make_swapchains(self.depth_format, usage)
        self.copier = SwapchainCopier(self.gl, self.platform, self.color_format)
        # What each frame's projection layer points at is fixed for the session: built once here.
        self._sub_images = [self._sub_image(self.swapchains, i) for i in range(self._view_count)]
        self._depth_infos = None
        if self.depth_swapchains:
            # nearZ/farZ are the distances of minDepth/maxDepth: reversed-Z swaps them (0 = infinity)
            near_z, far_z = (float("inf"), self.near) if self.reversed_z else (self.near, self.far)
            self._depth_infos = [xr.CompositionLayerDepthInfoKHR(
                sub_image=self._sub_image(self.depth_swapchains, i), min_depth=0.0, max_depth=1.0,
                near_z=near_z, far_z=far_z) for i in range(self._view_count)]

    def _make_swapchains(self, fmt: int, usage) -> list[_Swapchain]:
        xr = self.xr
        w, h = self._size
        n = self._view_count

        def create(array_size: int):
            return xr.create_swapchain(self.session, xr.SwapchainCreateInfo(
                usage_flags=usage, format=fmt, sample_count=1, width=w, height=h, face_count=1,
                array_size=array_size, mip_count=1))

        def images(handle) -> list[int]:
            return [int(i.image) for i in xr.enumerate_swapchain_images(handle, xr.SwapchainImageOpenGLKHR)]

        if self.want_array and n > 1:
            try:
                handle = create(n)
                return [_Swapchain(handle, images(handle), True, 0, n)]
            except xr.exception.ErrorResult:
                pass   # the runtime refuses array swapchains: one per view
        chains = []
        for v in range(n):
            handle = create(1)
            chains.append(_Swapchain(handle, images(handle), False, v, 1))
        return chains

    def _destroy_session(self) -> None:
        xr = self.xr
        if self.gaze is not None:
            self.gaze.destroy()
            self.gaze = None
        for sc in self.swapchains + self.depth_swapchains:
            try:
                xr.destroy_swapchain(sc.handle)
            except Exception:   # already gone with a lost session
                pass
        self.swapchains, self.depth_swapchains = [], []
        restore_stdin()   # Monado closes fd 0 when GL swapchains are destroyed
        for handle, destroy in ((self.space, "destroy_space"), (self.session, "destroy_session")):
            if handle is not None:
                try:
                    getattr(xr, destroy)(handle)
                except Exception:
                    pass
        self.space = self.session = None

    def _recover_session(self) -> bool:
        """After LOSS_PENDING: destroy the session, wait for the system, make a new session."""
        xr = self.xr
        self._destroy_session()
        deadline = time.monotonic() + self.recover_timeout_s
        while time.monotonic() < deadline:
            try:
                self._get_system()
                self._create_session()
                return True
            except (XrError, xr.exception.ErrorResult):
                time.sleep(0.1)
        return False

    # -- frame loop ---------------------------------------------------------------------------

    def _poll_events(self) -> None:
        xr = self.xr
        while True:
            try:
                event = xr.poll_event(self.instance)
            except xr.exception.EventUnavailable:
                return
            kind = int(event.type)
            if kind == int(xr.StructureType.EVENT_DATA_SESSION_STATE_CHANGED):
                changed = ctypes.cast(ctypes.byref(event), ctypes.POINTER(xr.EventDataSessionStateChanged)).contents
                self._on_state(changed.state)
            elif kind == int(xr.StructureType.EVENT_DATA_INSTANCE_LOSS_PENDING):
                self._instance_lost = True
                return

    def _on_state(self, state) -> None:
        xr = self.xr
        action = self.lifecycle.on_state_changed(int(state))
        if action is Action.BEGIN:
            xr.begin_session(self.session, xr.SessionBeginInfo(
                primary_view_configuration_type=xr.ViewConfigurationType.PRIMARY_STEREO))
            self.lifecycle.began()
        elif action is Action.END:
            xr.end_session(self.session)
            self.lifecycle.ended_session()

    def _settle_frame(self) -> None:
        """Begin and end (with no layers) a frame left waited-but-not-begun or begun-but-not-ended,
        so that the next xrWaitFrame cannot block on it. Runtime errors are ignored: the frame
        may already be gone with the session."""
        xr = self.xr
        if self.frame_phase is None or self.session is None:
            self.frame_phase = None
            return
        display_time = self._display_time or 0
        if self.frame_phase == "waiting":   # an interrupted xrWaitFrame never told its time: guess the next
            display_time += self._display_period or 1
        if self.frame_phase in ("waiting", "waited"):
            with contextlib.suppress(xr.exception.XrException):
                xr.begin_frame(self.session, xr.FrameBeginInfo())
            self.frame_phase = "begun"
        with contextlib.suppress(xr.exception.XrException):
            xr.end_frame(self.session, xr.FrameEndInfo(display_time=display_time,
                                                       environment_blend_mode=self.blend_mode, layers=[]))
        self.frame_phase = None

    def _begin_frame(self) -> FrameRequest:
        xr = self.xr
        self._settle_frame()
        self.frame_phase = "waiting"   # set before the call: Ctrl-C lands after it returns
        try:
            frame_state = xr.wait_frame(self.session, xr.FrameWaitInfo())
        except xr.exception.SessionLossPending:
            self.frame_phase = None
            self.lifecycle.on_state_changed(SessionState.LOSS_PENDING)
            return self._wait_frame()
        except xr.exception.XrException:
            self.frame_phase = None    # the runtime refused the call: no frame was waited
            raise
        self._display_time = frame_state.predicted_display_time
        self._display_period = getattr(frame_state, "predicted_display_period", 0)
        self.frame_phase = "waited"
        try:
            xr.begin_frame(self.session, xr.FrameBeginInfo())
        except xr.exception.FrameDiscarded:
            pass   # the previous frame was never ended; this one proceeds (spec: XR_FRAME_DISCARDED)
        self.frame_phase = "begun"
        view_state, located = xr.locate_views(self.session, xr.ViewLocateInfo(
            view_configuration_type=xr.ViewConfigurationType.PRIMARY_STEREO,
            display_time=frame_state.predicted_display_time, space=self.space))
        flags = int(view_state.view_state_flags)
        valid = bool(flags & int(xr.ViewStateFlags.ORIENTATION_VALID_BIT)) and \
            bool(flags & int(xr.ViewStateFlags.POSITION_VALID_BIT))
        views = views_from_located(located, self._size, self.near, self.far, self.reversed_z,
                                   self.world_pose, self._previous_views)
        self._previous_views = views
        if self.gaze is not None:
            direction = self.gaze.direction(self.space, frame_state.predicted_display_time, self.world_pose)
            if direction is not None:
                with contextlib.suppress(XrError):   # a gaze beside the views (a tracking glitch): none
                    views.gaze = direction_tangents(views, direction)
        return FrameRequest(self.frame_count, views, frame_state.predicted_display_time / 1e9,
                            should_render=bool(frame_state.should_render) and valid,
                            sink_data={"located": list(located), "display_time": frame_state.predicted_display_time})

    def _acquire(self, chains: list[_Swapchain]):
        xr = self.xr
        targets = []
        for sc in chains:
            index = xr.acquire_swapchain_image(sc.handle, xr.SwapchainImageAcquireInfo())
            xr.wait_swapchain_image(sc.handle, xr.SwapchainImageWaitInfo(timeout=xr.INFINITE_DURATION))
            target = GL_TEXTURE_2D_ARRAY if sc.array else GL_TEXTURE_2D
            targets.append((sc.images[index], target, 0, sc.first_view, sc.view_count))
        return targets

    def _release(self, chains: list[_Swapchain]) -> None:
        for sc in chains:
            self.xr.release_swapchain_image(sc.handle, self.xr.SwapchainImageReleaseInfo())

    def _sub_image(self, chains: list[_Swapchain], view: int):
        xr = self.xr
        w, h = self._size
        sc = chains[0] if chains[0].array else chains[view]
        return xr.SwapchainSubImage(swapchain=sc.handle,
                                    image_rect=xr.Rect2Di(offset=xr.Offset2Di(0, 0), extent=xr.Extent2Di(w, h)),
                                    image_array_index=view if sc.array else 0)


def restore_stdin() -> bool:
    """Put /dev/null back on file descriptor 0 if the runtime closed it (Monado does when GL
    swapchains are destroyed): otherwise the next file opened would become fd 0 and anything
    reading stdin would read it. True when fd 0 had to be restored."""
    try:
        os.fstat(0)
        return False
    except OSError:
        pass
    fd = os.open(os.devnull, os.O_RDONLY)
    if fd != 0:
        os.dup2(fd, 0)
        os.close(fd)
    return True
