"""OpenXRSink at the pyopenxr boundary: conversions, typed structs, the session lifecycle, and a
whole frame loop against a scripted fake runtime (real pyopenxr structs, real GL swapchain images)."""
import contextlib
import ctypes
import math
import os
import re
from collections import deque
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rayvr.errors import XrError
from rayvr.xr import Pose
from rayvr.xr.openxr_convert import (fov_from_xr, pose_from_xr, projection_views, views_from_located,
                                     xr_version)
from rayvr.xr.openxr_gl import GL_RGBA8, GL_RGBA16F, GL_SRGB8_ALPHA8, GLPlatform, choose_format
from rayvr.xr.openxr_lifecycle import Action, SessionLifecycle, SessionState
from rayvr.xr.openxr_sink import NO_RUNTIME, OpenXRSink

xr = pytest.importorskip("xr")
S = SessionState


def test_lifecycle_answers_each_state_with_the_spec_call():
    lc = SessionLifecycle()
    steps = [(S.IDLE, Action.NONE), (S.READY, Action.BEGIN), (S.SYNCHRONIZED, Action.NONE),
             (S.VISIBLE, Action.NONE), (S.FOCUSED, Action.NONE), (S.VISIBLE, Action.NONE),
             (S.SYNCHRONIZED, Action.NONE), (S.STOPPING, Action.END), (S.IDLE, Action.NONE),
             (S.EXITING, Action.EXIT)]
    for state, action in steps:
        assert lc.on_state_changed(state) is action, state
        if action is Action.BEGIN:
            lc.began()
        if action is Action.END:
            lc.ended_session()
    assert lc.anomalies == [] and lc.ended and not lc.running


def test_lifecycle_loss_pending_recovers_and_records_anomalies():
    lc = SessionLifecycle()
    lc.on_state_changed(S.IDLE)
    assert lc.on_state_changed(S.FOCUSED) is Action.NONE            # skipped READY..VISIBLE
    assert lc.anomalies == [(S.IDLE, S.FOCUSED)]
    assert lc.on_state_changed(S.LOSS_PENDING) is Action.RECOVER and lc.ended
    with pytest.raises(XrError, match="unknown session state 42"):
        SessionLifecycle().on_state_changed(42)


def test_exit_request_is_sent_once_while_running():
    lc = SessionLifecycle()
    lc.on_state_changed(S.IDLE)
    lc.on_state_changed(S.READY)
    lc.began()
    assert not lc.should_request_exit()
    lc.exit_requested = True
    assert lc.should_request_exit()
    lc.exit_sent = True
    assert not lc.should_request_exit()


def test_xr_pose_and_fov_become_rayvr_views():
    q = (0.1, 0.7, -0.2, 0.6)
    n = math.sqrt(sum(c * c for c in q))
    posef = xr.Posef(orientation=xr.Quaternionf(*(c / n for c in q)), position=xr.Vector3f(0.5, 1.7, -2.0))
    fovf = xr.Fovf(angle_left=-0.9, angle_right=0.8, angle_up=0.85, angle_down=-0.95)
    pose = pose_from_xr(posef)
    rot = pytest.importorskip("scipy.spatial.transform").Rotation.from_quat([c / n for c in q]).as_matrix()
    assert np.allclose(pose.rotation_matrix(), rot, atol=1e-6)
    assert np.allclose(pose.position, [0.5, 1.7, -2.0], atol=1e-6)
    located = [xr.View(pose=posef, fov=fovf)] * 2
    vs = views_from_located(located, (40, 30), 0.1, 100.0)
    l, r, u, d = (math.tan(a) for a in (-0.9, 0.8, 0.85, -0.95))
    # XrMatrix4x4f_CreateProjectionFov (OpenXR SDK, GRAPHICS_OPENGL), written out independently
    expected = np.array([[2 / (r - l), 0, (r + l) / (r - l), 0], [0, 2 / (u - d), (u + d) / (u - d), 0],
                         [0, 0, -(100 + 0.1) / (100 - 0.1), -2 * 100 * 0.1 / (100 - 0.1)], [0, 0, -1, 0]])
    assert np.allclose(vs[0].projection_matrix(), expected, atol=1e-6)
    world_from_eye = np.eye(4)
    world_from_eye[:3, :3], world_from_eye[:3, 3] = rot, [0.5, 1.7, -2.0]
    assert np.allclose(vs[0].view_matrix(), np.linalg.inv(world_from_eye), atol=1e-5)
    assert fov_from_xr(fovf).angle_up == pytest.approx(0.85)
    # a world pose moves the reference space into the scene
    placed = pose_from_xr(posef, Pose([10.0, 0.0, 0.0]))
    assert np.allclose(placed.position, [10.5, 1.7, -2.0], atol=1e-6)


def test_projection_views_are_typed_structs():
    located = [xr.View(pose=xr.Posef(), fov=xr.Fovf(-1, 1, 1, -1)), xr.View(pose=xr.Posef(), fov=xr.Fovf(-1, 1, 1, -1))]
    subs = [xr.SwapchainSubImage(image_array_index=i) for i in range(2)]
    arr = projection_views(xr, located, subs)
    assert [int(v.type) for v in arr] == [int(xr.StructureType.COMPOSITION_LAYER_PROJECTION_VIEW)] * 2
    assert [v.sub_image.image_array_index for v in arr] == [0, 1]
    layer = xr.CompositionLayerProjection(views=arr)
    assert layer.view_count == 2 and int(layer.views[1].type) == int(xr.StructureType.COMPOSITION_LAYER_PROJECTION_VIEW)


def test_swapchain_format_choice_prefers_srgb():
    assert choose_format([GL_RGBA8, GL_RGBA16F, GL_SRGB8_ALPHA8], (GL_SRGB8_ALPHA8, GL_RGBA16F, GL_RGBA8)) == GL_SRGB8_ALPHA8
    with pytest.raises(XrError, match="none of GL_SRGB8_ALPHA8"):
        choose_format([0x1234], (GL_SRGB8_ALPHA8,))


def _runtime_installed() -> bool:
    return bool(os.environ.get("XR_RUNTIME_JSON")) or Path("/etc/xdg/openxr/1/active_runtime.json").exists() \
        or Path.home().joinpath(".config/openxr/1/active_runtime.json").exists()


def test_no_runtime_message(gpu):
    class NoRuntime(SimpleNamespace):
        exception = xr.exception

        def enumerate_instance_extension_properties(self):
            raise xr.exception.RuntimeUnavailableError("The loader was unable to find or load a runtime.")

    with pytest.raises(XrError, match=f"^{re.escape(NO_RUNTIME)}$"):
        OpenXRSink(api=NoRuntime()).open(gpu)
    assert "XR_RUNTIME_JSON" in NO_RUNTIME and "SimulatedHeadset" in NO_RUNTIME
    if not _runtime_installed():      # the real loader, with nothing installed
        with pytest.raises(XrError) as info:
            OpenXRSink().open(gpu)
        assert str(info.value) == NO_RUNTIME


# --- a scripted runtime ------------------------------------------------------------------------

GL_TEXTURE_2D, GL_TEXTURE_2D_ARRAY, GL_RGBA, GL_UNSIGNED_BYTE = 0x0DE1, 0x8C1A, 0x1908, 0x1401
_U, _I = ctypes.c_uint, ctypes.c_int


def _handle(kind, value: int):
    """A real pyopenxr handle (typed pointer) with a recognisable value."""
    return ctypes.cast(ctypes.c_void_p(value), kind)


def _hid(handle) -> int:
    return ctypes.cast(handle, ctypes.c_void_p).value


class FakeRuntime:
    """Stands in for the pyopenxr module: real structs/enums via __getattr__, scripted calls."""

    def __init__(self, script, size=(16, 12), formats=(GL_SRGB8_ALPHA8, GL_RGBA8), array_ok=True):
        self._script = dict(script)      # frames ended -> states the runtime announces then
        self.size, self.formats, self.array_ok = size, formats, array_ok
        self.calls, self.frames_ended, self.layers = [], 0, []
        self.events = deque()
        self.textures = {}
        self.sessions = 0
        self._gl = GLPlatform()
        self._acquired = {}
        self._announce()

    def __getattr__(self, name):
        return getattr(xr, name)

    def _announce(self):
        for state in self._script.pop(self.frames_ended, []):
            self.events.append(state)

    def _log(self, name, *args):
        self.calls.append(name)

    # instance and system
    def enumerate_instance_extension_properties(self):
        self._log("enumerate_instance_extension_properties")
        return [SimpleNamespace(extension_name=e) for e in
                (b"XR_KHR_opengl_enable", b"XR_MNDX_egl_enable", b"XR_KHR_composition_layer_depth")]

    def create_instance(self, info):
        self._log("create_instance")
        self.enabled = [info.enabled_extension_names[i].decode() for i in range(info.enabled_extension_count)]
        return _handle(xr.Instance, 0x100)

    def get_system(self, instance, info):
        self._log("get_system")
        assert int(info.form_factor) == int(xr.FormFactor.HEAD_MOUNTED_DISPLAY)
        return 7

    def enumerate_view_configuration_views(self, instance, system, kind):
        assert int(kind) == int(xr.ViewConfigurationType.PRIMARY_STEREO)
        w, h = self.size
        return [SimpleNamespace(recommended_image_rect_width=w, recommended_image_rect_height=h)] * 2

    def enumerate_environment_blend_modes(self, instance, system, kind):
        return [xr.EnvironmentBlendMode.OPAQUE]

    def get_opengl_graphics_requirements_khr(self, instance, system):
        self._log("get_opengl_graphics_requirements_khr")
        return SimpleNamespace(min_api_version_supported=xr_version(4, 0), max_api_version_supported=xr_version(4, 6))

    # session
    def create_session(self, instance, info):
        self._log("create_session")
        binding = ctypes.cast(info.next, ctypes.POINTER(xr.GraphicsBindingEGLMNDX)).contents
        assert int(binding.type) == int(xr.StructureType.GRAPHICS_BINDING_EGL_MNDX)
        assert ctypes.cast(binding.display, ctypes.c_void_p).value and ctypes.cast(binding.context, ctypes.c_void_p).value
        assert ctypes.cast(binding.config, ctypes.c_void_p).value
        self.sessions += 1
        if not self.events:
            self.events.extend([S.IDLE, S.READY])
        return _handle(xr.Session, 0x200 + self.sessions)

    def enumerate_reference_spaces(self, session):
        return [xr.ReferenceSpaceType.VIEW, xr.ReferenceSpaceType.LOCAL, xr.ReferenceSpaceType.STAGE]

    def create_reference_space(self, session, info):
        self.space_type = int(info.reference_space_type)
        return _handle(xr.Space, 0x300)

    def enumerate_swapchain_formats(self, session):
        return list(self.formats)

    def create_swapchain(self, session, info):
        if info.array_size > 1 and not self.array_ok:
            raise xr.exception.FeatureUnsupportedError("no array swapchains")
        self._log(f"create_swapchain:{info.array_size}")
        self.format = info.format
        images = []
        for _ in range(3):
            names = (_U * 1)()
            target = GL_TEXTURE_2D_ARRAY if info.array_size > 1 else GL_TEXTURE_2D
            self._gl.proc("glCreateTextures", None, [_U, _I, ctypes.POINTER(_U)])(target, 1, names)
            if target == GL_TEXTURE_2D_ARRAY:
                self._gl.proc("glTextureStorage3D", None, [_U, _I, _U, _I, _I, _I])(
                    names[0], 1, info.format, info.width, info.height, info.array_size)
            else:
                self._gl.proc("glTextureStorage2D", None, [_U, _I, _U, _I, _I])(
                    names[0], 1, info.format, info.width, info.height)
            images.append(names[0])
        handle = 0x400 + len(self.textures)
        self.textures[handle] = (images, info.array_size)
        return _handle(xr.Swapchain, handle)

    def enumerate_swapchain_images(self, handle, kind):
        return [SimpleNamespace(image=i) for i in self.textures[_hid(handle)][0]]

    def poll_event(self, instance):
        if not self.events:
            raise xr.exception.EventUnavailable()
        buf = xr.EventDataBuffer()
        ev = ctypes.cast(ctypes.byref(buf), ctypes.POINTER(xr.EventDataSessionStateChanged)).contents
        ev._type = int(xr.StructureType.EVENT_DATA_SESSION_STATE_CHANGED)
        ev._state = int(self.events.popleft())
        return buf

    def begin_session(self, session, info):
        self._log("begin_session")
        assert int(info.primary_view_configuration_type) == int(xr.ViewConfigurationType.PRIMARY_STEREO)

    def end_session(self, session):
        self._log("end_session")
        self.events.extend([S.IDLE, S.EXITING])

    def request_exit_session(self, session):
        self._log("request_exit_session")
        down = {S.FOCUSED: [S.VISIBLE, S.SYNCHRONIZED], S.VISIBLE: [S.SYNCHRONIZED]}.get(self._state, [])
        self.events.extend([*down, S.STOPPING])

    # frames
    waited_not_begun = False

    def wait_frame(self, session, info):
        self._log("wait_frame")
        if self.waited_not_begun:   # the specification: this xrWaitFrame would block until xrBeginFrame
            raise AssertionError("xrWaitFrame called while the previous frame was waited and never begun: "
                                 "a real runtime blocks here forever")
        self.waited_not_begun = True
        self.state_at_wait = self._state
        visible = self._state in (S.VISIBLE, S.FOCUSED)
        return SimpleNamespace(predicted_display_time=1_000_000_000 + 11_111_111 * self.frames_ended,
                               predicted_display_period=11_111_111, should_render=int(visible))

    _state = S.UNKNOWN

    def begin_frame(self, session, info):
        self._log("begin_frame")
        self.waited_not_begun = False

    def locate_views(self, session, info):
        assert _hid(info.space) == 0x300
        views = [xr.View(pose=xr.Posef(position=xr.Vector3f(x, 1.6, 0.0)), fov=xr.Fovf(-0.9, 0.8, 0.85, -0.95))
                 for x in (-0.032, 0.032)]
        return SimpleNamespace(view_state_flags=0xF), views

    def acquire_swapchain_image(self, handle, info):
        h = _hid(handle)
        self._acquired[h] = (self._acquired.get(h, -1) + 1) % 3
        return self._acquired[h]

    def wait_swapchain_image(self, handle, info):
        assert info.timeout == xr.INFINITE_DURATION

    def release_swapchain_image(self, handle, info):
        self._log("release_swapchain_image")

    def end_frame(self, session, info):
        self._log("end_frame")
        layers = []
        for i in range(info.layer_count):
            layer = ctypes.cast(info.layers[i], ctypes.POINTER(xr.CompositionLayerProjection)).contents
            assert int(layer.type) == int(xr.StructureType.COMPOSITION_LAYER_PROJECTION)
            layers.append([(int(v.type), _hid(v.sub_image.swapchain), v.sub_image.image_array_index,
                            v.sub_image.image_rect.extent.width, v.fov.angle_left, v.pose.position.x)
                           for v in layer.views])
            self.depth_infos = [ctypes.cast(v.next, ctypes.POINTER(xr.CompositionLayerDepthInfoKHR)).contents
                                if v.next else None for v in layer.views]
        self.layers.append(layers)
        self.frames_ended += 1
        self._announce()

    def destroy_swapchain(self, h):
        self._log("destroy_swapchain")

    def destroy_space(self, h):
        self._log("destroy_space")

    def destroy_session(self, h):
        self._log("destroy_session")

    def destroy_instance(self, h):
        self._log("destroy_instance")

    def read_image(self, name, layers, w, h):
        out = np.zeros((layers, h, w, 4), np.uint8)
        self._gl.proc("glGetTextureImage", None, [_U, _I, _U, _U, _I, ctypes.c_void_p])(
            name, 0, GL_RGBA, GL_UNSIGNED_BYTE, out.nbytes, out.ctypes.data)
        return out


class TrackingRuntime(FakeRuntime):
    """Keeps `_state` in step with the events it hands out, as a runtime would."""

    def poll_event(self, instance):
        buf = super().poll_event(instance)
        self._state = S(ctypes.cast(ctypes.byref(buf), ctypes.POINTER(xr.EventDataSessionStateChanged)).contents._state)
        return buf


def _eyes(gl, w, h):
    data = np.zeros((2, h, w, 4), np.uint8)
    data[0, ..., 0], data[1, ..., 1] = 180, 90
    data[..., 2] = np.arange(w, dtype=np.uint8)[None, None, :] * 5
    data[..., 3] = 255
    return data, gl.texture_array((w, h, 2), 4, data.tobytes())


def _run(sink, gpu, tex):
    sink.open(gpu)
    requests = []
    while (r := sink.wait_frame()) is not None:
        sink.submit(tex if r.should_render else None, r)
        requests.append(r)
    sink.close()
    return requests


def test_frame_loop_follows_the_lifecycle_and_submits_typed_layers(gpu, gl):
    rt = TrackingRuntime({1: [S.SYNCHRONIZED], 2: [S.VISIBLE, S.FOCUSED]})
    sink = OpenXRSink(api=rt, frames=4)
    data, tex = _eyes(gl, 16, 12)
    requests = _run(sink, gpu, tex)
    assert sink.lifecycle.history == [S.UNKNOWN, S.IDLE, S.READY, S.SYNCHRONIZED, S.VISIBLE, S.FOCUSED,
                                      S.VISIBLE, S.SYNCHRONIZED, S.STOPPING, S.IDLE, S.EXITING]
    assert sink.lifecycle.anomalies == []
    calls = rt.calls
    assert calls.index("get_opengl_graphics_requirements_khr") < calls.index("create_session")
    assert calls.index("begin_session") < calls.index("wait_frame")
    assert calls.count("wait_frame") == calls.count("begin_frame") == calls.count("end_frame") == len(requests)
    assert calls.index("request_exit_session") < calls.index("end_session") < calls.index("destroy_session")
    assert calls[-1] == "destroy_instance" and "create_swapchain:2" in calls    # one array swapchain
    assert rt.enabled == ["XR_KHR_opengl_enable", "XR_MNDX_egl_enable"]
    assert rt.space_type == int(xr.ReferenceSpaceType.STAGE)
    # frames before VISIBLE end with no layers; visible ones carry one projection layer of 2 typed views
    rendered = [r.should_render for r in requests]
    assert rendered[:2] == [False, False] and all(rendered[2:4])
    for layers, r in zip(rt.layers, requests):
        assert len(layers) == (1 if r.should_render else 0)
    view_type = int(xr.StructureType.COMPOSITION_LAYER_PROJECTION_VIEW)
    views = rt.layers[2][0]
    assert [(v[0], v[2], v[3]) for v in views] == [(view_type, 0, 16), (view_type, 1, 16)]
    assert views[0][4] == pytest.approx(-0.9) and views[1][5] == pytest.approx(0.032)
    # the located poses became the request's views, in the stage space
    assert np.allclose(requests[2].views[1].pose.position, [0.032, 1.6, 0.0], atol=1e-6)
    assert requests[2].predicted_display_time == pytest.approx(1.0 + 0.011111111 * 2)
    # the swapchain image holds exactly the rendered texels (rgba8 sRGB-encoded -> GL_SRGB8_ALPHA8)
    images, layers = rt.textures[0x400]
    got = rt.read_image(images[0], 2, 16, 12)
    assert rt.format == GL_SRGB8_ALPHA8
    assert np.array_equal(got, data)


def test_per_eye_swapchains_when_arrays_are_refused_and_linear_rgba8(gpu, gl):
    rt = TrackingRuntime({0: [], 1: [S.SYNCHRONIZED, S.VISIBLE]}, formats=(GL_RGBA8,), array_ok=False)
    sink = OpenXRSink(api=rt, frames=2)
    data, tex = _eyes(gl, 16, 12)
    _run(sink, gpu, tex)
    assert rt.calls.count("create_swapchain:1") == 2
    visible = [l for l in rt.layers if l]
    assert [(v[1], v[2]) for v in visible[0][0]] == [(0x400, 0), (0x401, 0)]
    # sRGB-encoded source into a linear swapchain: decoded to linear on the GPU
    left = rt.read_image(rt.textures[0x400][0][0], 1, 16, 12)[0]
    c = 180 / 255
    assert abs(int(left[0, 0, 0]) - round(((c + 0.055) / 1.055) ** 2.4 * 255)) <= 1
    right = rt.read_image(rt.textures[0x401][0][0], 1, 16, 12)[0]
    assert right[0, 0, 0] == 0 and right[0, 0, 1] > 0


def test_loss_pending_recreates_the_session(gpu, gl):
    rt = TrackingRuntime({1: [S.SYNCHRONIZED], 2: [S.LOSS_PENDING]})
    sink = OpenXRSink(api=rt, frames=4)
    _, tex = _eyes(gl, 16, 12)
    _run(sink, gpu, tex)
    assert rt.sessions == 2 and rt.calls.count("create_session") == 2
    assert rt.calls.index("destroy_session") < len(rt.calls) - 1 - rt.calls[::-1].index("create_session")
    assert sink.lifecycle.history[-1] == S.EXITING
    assert rt.frames_ended >= 4


def test_size_and_view_count_come_from_the_runtime_before_open(gpu):
    rt = TrackingRuntime({})
    sink = OpenXRSink(api=rt)
    assert (sink.view_count, sink.size) == (2, (16, 12))
    assert "create_session" not in rt.calls and rt.calls.count("create_instance") == 1
    sink.open(gpu)
    assert rt.calls.count("create_instance") == 1 and "create_session" in rt.calls
    sink.close()


def test_depth_submission_chains_depth_info_to_each_view(gpu, gl):
    from rayvr.xr.openxr_gl import GL_DEPTH_COMPONENT32F

    rt = TrackingRuntime({1: [S.SYNCHRONIZED, S.VISIBLE]}, formats=(GL_SRGB8_ALPHA8, GL_DEPTH_COMPONENT32F))
    sink = OpenXRSink(api=rt, depth=True, near=0.1, far=50.0, frames=3)
    _, tex = _eyes(gl, 16, 12)
    names = (_U * 1)()
    rt._gl.proc("glCreateTextures", None, [_U, _I, ctypes.POINTER(_U)])(GL_TEXTURE_2D_ARRAY, 1, names)
    rt._gl.proc("glTextureStorage3D", None, [_U, _I, _U, _I, _I, _I])(names[0], 1, GL_DEPTH_COMPONENT32F, 16, 12, 2)
    depth = SimpleNamespace(glo=names[0], width=16, height=12)
    sink.open(gpu)
    while (r := sink.wait_frame()) is not None:
        sink.submit(tex if r.should_render else None, r, depth_array=depth if r.should_render else None)
    sink.close()
    assert "XR_KHR_composition_layer_depth" in rt.enabled
    assert rt.calls.count("create_swapchain:2") == 2          # colour and depth, both arrays
    info = rt.depth_infos[1]
    assert int(info.type) == int(xr.StructureType.COMPOSITION_LAYER_DEPTH_INFO_KHR)
    assert (info.min_depth, info.max_depth) == (0.0, 1.0)
    assert info.near_z == pytest.approx(0.1) and info.far_z == pytest.approx(50.0)
    assert info.sub_image.image_array_index == 1 and _hid(info.sub_image.swapchain) == 0x401


def test_runtime_failures_become_xr_errors_naming_the_step(gpu):
    class Failing(TrackingRuntime):
        def get_system(self, instance, info):
            raise xr.exception.InitializationFailedError("Initialization of object could not be completed.")

    with pytest.raises(XrError, match="failed while creating the instance and system.*InitializationFailedError"):
        OpenXRSink(api=Failing({})).open(gpu)

    class NoHmd(TrackingRuntime):
        def get_system(self, instance, info):
            raise xr.exception.FormFactorUnavailableError("unavailable")

    with pytest.raises(XrError, match="found no headset"):
        OpenXRSink(api=NoHmd({})).size


class InterruptedWait(TrackingRuntime):
    """Ctrl-C arrives while xrWaitFrame of frame `at` blocks: the wait completes in the runtime,
    then Python raises KeyboardInterrupt before the sink sees the result."""

    def __init__(self, script, at, **kw):
        super().__init__(script, **kw)
        self.at = at

    def wait_frame(self, session, info):
        state = super().wait_frame(session, info)
        if self.calls.count("wait_frame") == self.at:
            raise KeyboardInterrupt
        return state


def test_ctrl_c_inside_wait_frame_begins_and_ends_that_frame_before_waiting_again(gpu, gl):
    rt = InterruptedWait({1: [S.SYNCHRONIZED, S.VISIBLE]}, at=3)
    sink = OpenXRSink(api=rt)
    _, tex = _eyes(gl, 16, 12)
    sink.open(gpu)
    with pytest.raises(KeyboardInterrupt):
        while (r := sink.wait_frame()) is not None:
            sink.submit(tex if r.should_render else None, r)
    assert sink.frame_phase == "waiting" and rt.frames_ended == 2
    sink.close()       # the fake raises, as a real runtime would hang, if it waits before beginning
    frame_calls = [c for c in rt.calls if c in ("wait_frame", "begin_frame", "end_frame")]
    assert frame_calls[6:9] == ["wait_frame", "begin_frame", "end_frame"]   # the interrupted frame, settled
    assert rt.layers[2] == []                                                # with no layers
    assert sink.lifecycle.history[-1] == S.EXITING and sink.frame_phase is None
    assert rt.calls[-1] == "destroy_instance"


def test_a_begun_frame_left_unsubmitted_is_ended_with_no_layers_on_close(gpu, gl):
    rt = TrackingRuntime({1: [S.SYNCHRONIZED, S.VISIBLE]})
    sink = OpenXRSink(api=rt)
    sink.open(gpu)
    for _ in range(3):
        r = sink.wait_frame()
        sink.submit(None, r)
    r = sink.wait_frame()                        # then the application dies (Ctrl-C) mid-frame
    assert sink.frame_phase == "begun"
    ended = rt.frames_ended
    sink.close()
    assert rt.frames_ended > ended and rt.layers[ended] == []
    waits = [i for i, c in enumerate(rt.calls) if c == "wait_frame"]
    assert rt.calls.index("end_frame", waits[3]) < waits[4]   # ended before the next wait
    assert sink.lifecycle.history[-1] == S.EXITING


@pytest.mark.parametrize("where, step", [("wait_frame", "waiting for the next frame"),
                                         ("end_frame", "submitting frame 0"),
                                         ("begin_session", "waiting for the next frame")])
def test_runtime_errors_in_the_frame_loop_are_xr_errors(gpu, gl, where, step):
    class Failing(TrackingRuntime):
        pass

    def fail(self, *args):
        raise xr.exception.RuntimeFailureError("the runtime fell over")

    setattr(Failing, where, fail)
    rt = Failing({1: [S.SYNCHRONIZED, S.VISIBLE]})
    sink = OpenXRSink(api=rt, frames=2)
    sink.open(gpu)
    with pytest.raises(XrError, match=f"OpenXR runtime failed while {step}: .*RuntimeFailureError"):
        while (r := sink.wait_frame()) is not None:
            sink.submit(None, r)
    sink.close()


def test_depth_sink_driven_by_the_renderer_refuses_instead_of_dropping_depth(gpu, gl):
    import rayvr as rv
    from rayvr.xr.openxr_gl import GL_DEPTH_COMPONENT32F

    rt = TrackingRuntime({1: [S.SYNCHRONIZED, S.VISIBLE]}, formats=(GL_SRGB8_ALPHA8, GL_DEPTH_COMPONENT32F))
    sink = OpenXRSink(api=rt, depth=True, frames=4)
    with pytest.raises(XrError, match=r"depth=True.*without depth_array.*depth=False"):
        with rv.Renderer(rv.scenes.quad(), rv.graphs.hybrid(preset="raw"), sink=sink) as r:
            for _ in r.frames():
                pass
    assert rt.calls[-1] == "destroy_instance"          # closed cleanly all the same
    # the same sink without depth runs under the Renderer, and creates no depth swapchain
    rt = TrackingRuntime({1: [S.SYNCHRONIZED, S.VISIBLE]}, formats=(GL_SRGB8_ALPHA8, GL_DEPTH_COMPONENT32F))
    sink = OpenXRSink(api=rt, frames=3)
    with rv.Renderer(rv.scenes.quad(), rv.graphs.hybrid(preset="raw"), sink=sink) as r:
        assert sum(1 for _ in r.frames()) >= 3
    assert rt.calls.count("create_swapchain:2") == 1 and not sink.depth_swapchains


def test_stdin_is_put_back_when_the_runtime_closes_fd_0(gpu, gl):
    class ClosesStdin(TrackingRuntime):
        def destroy_swapchain(self, h):   # as Monado does on GL swapchain destroy
            super().destroy_swapchain(h)
            with contextlib.suppress(OSError):
                os.close(0)

    saved = os.dup(0)
    try:
        rt = ClosesStdin({1: [S.SYNCHRONIZED, S.VISIBLE]})
        _run(OpenXRSink(api=rt, frames=2), gpu, _eyes(gl, 16, 12)[1])
        assert os.fstat(0).st_rdev == os.stat(os.devnull).st_rdev
        probe = os.open(os.devnull, os.O_RDONLY)
        assert probe != 0                                  # new files no longer land on fd 0
        os.close(probe)
    finally:
        os.dup2(saved, 0)
        os.close(saved)


class EyeGazeRuntime(TrackingRuntime):
    """Offers XR_EXT_eye_gaze_interaction (or not: `offered`) and tracks the eyes looking
    `yaw_deg` to the right of the head's forward."""

    def __init__(self, *args, offered=True, yaw_deg=20.0, **kw):
        super().__init__(*args, **kw)
        self.offered, self.yaw = offered, math.radians(yaw_deg)
        self.raw_functions = SimpleNamespace(xrGetSystemProperties=self._system_properties)

    def enumerate_instance_extension_properties(self):
        names = super().enumerate_instance_extension_properties()
        return names + ([SimpleNamespace(extension_name=b"XR_EXT_eye_gaze_interaction")] if self.offered else [])

    def _system_properties(self, instance, system, props):
        p = ctypes.cast(props, ctypes.POINTER(xr.SystemProperties)).contents
        eye = ctypes.cast(p.next, ctypes.POINTER(xr.SystemEyeGazeInteractionPropertiesEXT)).contents
        eye.supports_eye_gaze_interaction = 1
        return 0

    def string_to_path(self, instance, text):
        self._log(f"path:{text}")
        return 0x900 + len(self.calls)

    def create_action_set(self, instance, info):
        self._log("create_action_set")
        return _handle(xr.ActionSet, 0x500)

    def create_action(self, action_set, info):
        self._log("create_action")
        assert int(info.action_type) == int(xr.ActionType.POSE_INPUT)
        return _handle(xr.Action, 0x600)

    def suggest_interaction_profile_bindings(self, instance, bindings):
        self._log("suggest_interaction_profile_bindings")

    def attach_session_action_sets(self, session, info):
        self._log("attach_session_action_sets")

    def create_action_space(self, session, info):
        self._log("create_action_space")
        return _handle(xr.Space, 0x700)

    def sync_actions(self, session, info):
        self._log("sync_actions")

    def locate_space(self, space, base, time):
        assert _hid(space) == 0x700 and _hid(base) == 0x300
        half = -self.yaw / 2   # a turn to the right is negative about +Y
        location = xr.SpaceLocation(pose=xr.Posef(orientation=xr.Quaternionf(0.0, math.sin(half), 0.0, math.cos(half))))
        location.location_flags = int(xr.SpaceLocationFlags.ORIENTATION_VALID_BIT) | \
            int(xr.SpaceLocationFlags.ORIENTATION_TRACKED_BIT)
        return location

    def destroy_action_set(self, h):
        self._log("destroy_action_set")


@pytest.mark.parametrize("offered", [True, False])
def test_eye_gaze_is_enabled_where_offered_and_each_frame_carries_the_gaze(gpu, gl, offered):
    rt = EyeGazeRuntime({1: [S.SYNCHRONIZED, S.VISIBLE]}, offered=offered)
    requests = _run(OpenXRSink(api=rt, frames=3), gpu, _eyes(gl, 16, 12)[1])
    assert ("XR_EXT_eye_gaze_interaction" in rt.enabled) is offered
    rendered = [r for r in requests if r.should_render]
    assert rendered
    if not offered:
        assert "create_action_set" not in rt.calls and all(r.views.gaze is None for r in requests)
        return
    calls = rt.calls
    assert "path:/user/eyes_ext/input/gaze_ext/pose" in calls
    assert "path:/interaction_profiles/ext/eye_gaze_interaction" in calls
    assert calls.index("suggest_interaction_profile_bindings") < calls.index("attach_session_action_sets")
    assert calls.count("sync_actions") == len(requests)
    assert calls.index("destroy_action_set") < calls.index("destroy_session")
    # both eyes look straight ahead in the fake: the gaze's tangent is tan(20 degrees) to the right
    assert np.allclose(rendered[0].views.gaze, [[math.tan(math.radians(20.0)), 0.0]] * 2, atol=1e-6)


@pytest.mark.skipif(not os.environ.get("RAYVR_TEST_OPENXR"), reason="set RAYVR_TEST_OPENXR=1 with a runtime "
                    "(e.g. Monado: XR_RUNTIME_JSON=... XRT_COMPOSITOR_NULL=1 SIMULATED_ENABLE=1)")
def test_real_runtime_round_trip(gpu, gl):
    """Against the machine's runtime with the core validation layer: lifecycle and swapchain texels."""
    sink = OpenXRSink(frames=6, validation=True)
    w, h = sink.size
    data = np.zeros((2, h, w, 4), np.uint8)
    data[0, ..., 0], data[1, ..., 1], data[..., 3] = 200, 100, 255
    tex = gl.texture_array((w, h, 2), 4, data.tobytes())
    sink.open(gpu)
    matched = False
    get = sink.platform.proc("glGetTextureImage", None, [_U, _I, _U, _U, _I, ctypes.c_void_p])
    while (r := sink.wait_frame()) is not None:
        sink.submit(tex if r.should_render else None, r)
        if r.should_render and sink.swapchains[0].array:
            for image in sink.swapchains[0].images:
                out = np.zeros_like(data)
                get(image, 0, GL_RGBA, GL_UNSIGNED_BYTE, out.nbytes, out.ctypes.data)
                matched |= np.array_equal(out, data)
    sink.close()
    assert matched and sink.lifecycle.anomalies == []
    assert sink.lifecycle.history[-1] == S.EXITING and sink.frame_count >= 6
