"""The viewer's parts that need no display: camera controllers, views, input, scripts,
assignments, camera paths, and the one-line errors without a display or the viewer extra."""
from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import rayvr as rv
from rayvr.cli.main import main
from rayvr.errors import OptionError, XrError
from rayvr.viewer.camera import CameraRig, FlyCamera, OrbitCamera, orientation, yaw_pitch
from rayvr.viewer.display import fit
from rayvr.viewer.input import InputEvent, InputState
from rayvr.viewer.script import InputScript, ScriptAction
from rayvr.viewer.view_rig import ViewRig
from rayvr.xr.camera_path import CameraPath
from rayvr.xr.cameras import default_views
from rayvr.xr.views import Pose

KEYS = {"W", "A", "S", "D", "E", "Q", "H", "LEFT_SHIFT", "F12", "SPACE"}


def held(*keys, drag=(0.0, 0.0), buttons=(), scroll=0.0) -> InputState:
    s = InputState()
    s.keys_down = set(keys)
    s.drag, s.drag_buttons, s.scroll = drag, set(buttons), scroll
    return s


def forward_of(pose: Pose) -> np.ndarray:
    return pose.rotation_matrix() @ np.array([0.0, 0.0, -1.0])


# -- camera -----------------------------------------------------------------------------------
@pytest.mark.parametrize("yaw,pitch", [(0.0, 0.0), (0.7, -0.3), (-2.5, 1.2), (3.0, 0.01)])
def test_yaw_pitch_round_trip(yaw, pitch):
    assert yaw_pitch(Pose(np.zeros(3), orientation(yaw, pitch))) == pytest.approx((yaw, pitch), abs=1e-12)


def test_fly_moves_speed_times_dt_along_the_view_and_shift_is_four_times():
    start = Pose([1.0, 2.0, 3.0], orientation(0.6, -0.2))
    cam = FlyCamera(start, speed=2.0)
    cam.update(held("W"), 0.25)
    np.testing.assert_allclose(cam.position - start.position, 0.5 * forward_of(start), atol=1e-12)
    cam = FlyCamera(start, speed=2.0)
    cam.update(held("W", "LEFT_SHIFT"), 0.25)
    np.testing.assert_allclose(np.linalg.norm(cam.position - start.position), 2.0, rtol=1e-12)
    cam = FlyCamera(start, speed=2.0)
    cam.update(held("D", "E"), 0.5)        # diagonal: still `speed` m/s, in the head's right-up plane
    step = cam.position - start.position
    rot = start.rotation_matrix()
    np.testing.assert_allclose(step, rot @ (np.array([1.0, 1.0, 0.0]) / math.sqrt(2)), atol=1e-12)


def test_fly_look_turns_by_the_drag_and_clamps_pitch():
    cam = FlyCamera(Pose(np.zeros(3), orientation(0.0, 0.0)))
    cam.update(held(drag=(100.0, 0.0), buttons={1}), 0.0)
    assert cam.yaw == pytest.approx(-0.5) and cam.pitch == 0.0        # right drag turns right
    cam.update(held(drag=(0.0, -1e5), buttons={0}), 0.0)
    assert cam.pitch == pytest.approx(math.radians(89.0))
    cam.update(held(drag=(50.0, 50.0)), 0.0)                           # no button held: no look
    assert cam.yaw == pytest.approx(-0.5)
    speed = cam.speed
    cam.update(held(scroll=2.0), 0.0)
    assert cam.speed == pytest.approx(speed * 1.44)


def test_orbit_keeps_its_distance_and_looks_at_the_target():
    target = np.array([0.5, 0.0, -1.0])
    start = rv.xr.look_at([0.5, 1.0, 2.0], target)
    cam = OrbitCamera(start, target)
    d = np.linalg.norm(start.position - target)
    assert cam.distance == pytest.approx(d)
    cam.update(held(drag=(80.0, 30.0), buttons={0}), 0.0)
    pose = cam.pose
    assert np.linalg.norm(pose.position - target) == pytest.approx(d)
    np.testing.assert_allclose(forward_of(pose), (target - pose.position) / d, atol=1e-12)
    cam.update(held(scroll=1.0), 0.0)
    assert cam.distance == pytest.approx(0.9 * d)


def test_rig_switches_modes_without_moving_and_resets():
    home = rv.xr.look_at([0.0, 0.3, 1.0], [0.0, 0.3, 0.0])
    rig = CameraRig(home, centre=[0.0, 0.25, 0.0], speed=1.0)
    rig.update(held("W", "A"), 0.1)
    rig.update(held(drag=(20.0, 10.0), buttons={0}), 0.0)
    before = rig.pose
    rig.set_mode("orbit")
    np.testing.assert_allclose(rig.pose.position, before.position, atol=1e-12)
    np.testing.assert_allclose(forward_of(rig.pose), forward_of(before), atol=1e-12)
    rig.set_mode("fly")
    np.testing.assert_allclose(rig.pose.position, before.position, atol=1e-12)
    rig.reset()
    np.testing.assert_allclose(rig.pose.position, home.position, atol=1e-12)
    with pytest.raises(OptionError, match="camera mode 'walk'"):
        rig.set_mode("walk")


# -- views -------------------------------------------------------------------------------------
def test_rig_from_scene_matches_rayvr_render_views_and_stereo_ipd():
    scene = rv.scenes.cornell_box()
    rig = ViewRig.from_scene(scene, 2, (96, 64), ipd=0.07)
    base = default_views(scene, 1, (96, 64))[0]
    assert rig.fov_left == base.fov and (rig.near, rig.far) == (base.near, base.far)
    head = Pose([0.1, 0.2, 0.3], orientation(0.4, 0.1))
    views = rig.view_set(head)
    assert len(views) == 2 and views.size == (96, 64)
    np.testing.assert_allclose(views[1].pose.position - views[0].pose.position,
                               head.rotation_matrix() @ [0.07, 0.0, 0.0], atol=1e-12)
    mono = ViewRig.from_scene(scene, 1, (96, 64)).view_set(head)
    assert len(mono) == 1 and np.allclose(mono[0].pose.position, head.position)
    with pytest.raises(OptionError, match="1 \\(mono\\) or 2"):
        ViewRig.from_scene(scene, 3, (8, 8))


def test_headset_preset_sets_scaled_size_fov_and_ipd():
    rig = ViewRig.from_scene(rv.scenes.cornell_box(), 1, (64, 64)).with_preset("quest2", 0.1)
    p = rv.xr.get_preset("quest2")
    assert rig.views == 2 and rig.size == (183, 192) and rig.ipd == p.ipd and rig.preset == "quest2"
    assert rig.fov_left == p.left_fov and rig.fov_right == p.right_fov
    with pytest.raises(OptionError, match="unknown headset preset 'quest'"):
        rig.with_preset("quest")
    fov = rig.with_vertical_fov(60.0)
    assert fov.preset is None and fov.vertical_fov_deg == pytest.approx(60.0)


def test_fit_keeps_aspect_and_is_exact_when_sizes_match():
    assert fit((256, 128), (256, 128)) == (0, 0, 256, 128)
    assert fit((128, 128), (256, 128)) == (64, 0, 128, 128)
    assert fit((200, 100), (100, 100)) == (0, 25, 100, 50)


# -- input and scripts ---------------------------------------------------------------------------
def test_input_state_leaves_to_the_ui_what_it_wants():
    s = InputState()
    s.ui_wants_keyboard = True
    s.handle(InputEvent("key", key="W", down=True))
    assert not s.held("W")
    s.ui_wants_keyboard = False
    s.handle(InputEvent("key", key="W", down=True))
    assert s.held("W") and "W" in s.pressed
    s.handle(InputEvent("key", key="W", down=False))
    assert not s.held("W")
    s.handle(InputEvent("move", x=10, y=10))
    s.ui_wants_mouse = True
    s.handle(InputEvent("button", button=0, down=True))   # pressed on a panel: no camera drag
    s.handle(InputEvent("move", x=30, y=15))
    assert s.drag == (0.0, 0.0)
    s.handle(InputEvent("button", button=0, down=False))
    s.ui_wants_mouse = False
    s.handle(InputEvent("button", button=1, down=True))
    s.handle(InputEvent("move", x=40, y=5))
    assert s.drag == (10.0, -10.0)
    s.begin_frame()
    assert s.drag == (0.0, 0.0) and not s.pressed and 1 in s.drag_buttons


def test_script_parses_events_by_frame():
    script = InputScript.parse({"dt": 0.05, "events": [
        {"frame": 1, "key": "W", "action": "tap"},
        {"frame": 2, "mouse": [3, 4]}, {"frame": 2, "button": "right", "action": "down"},
        {"frame": 3, "scroll": -1}, {"frame": 3, "text": "ab"},
        {"frame": 4, "screenshot": "a.png"}, {"frame": 4, "effect": {"Floor": "raster"}}, {"frame": 5, "quit": True}]},
        KEYS)
    assert script.dt == 0.05 and script.last_frame == 5
    assert script.at(1) == [InputEvent("key", key="W", down=True)]
    assert InputEvent("key", key="W", down=False) in script.at(2)
    assert InputEvent("move", x=3.0, y=4.0) in script.at(2) and InputEvent("button", button=1, down=True) in script.at(2)
    assert script.at(3) == [InputEvent("scroll", dy=-1.0), InputEvent("char", char=ord("a")),
                            InputEvent("char", char=ord("b"))]
    assert script.at(4) == [ScriptAction("screenshot", "a.png"), ScriptAction("effect", {"Floor": "raster"})]
    assert script.at(5) == [ScriptAction("quit")]


@pytest.mark.parametrize("events,message", [
    ([{"frame": 1, "key": "WW"}], r"events\[0\]\.key: unknown key 'WW' \(did you mean 'W'\?\)"),
    ([{"frame": -1, "key": "W"}], r"events\[0\]\.frame: expected a frame number >= 0"),
    ([{"frame": 1, "key": "W", "mouse": [1, 2]}], r"events\[0\]: give exactly one of"),
    ([{"frame": 1, "kye": "W"}], r"unknown field 'kye' \(did you mean 'key'\?\)"),
    ([{"frame": 1, "key": "W", "action": "hold"}], r"events\[0\]\.action: 'hold' is not one of down, up, tap"),
    ([{"frame": 0}, ], r"events\[0\]: give exactly one of"),
    ([{"frame": 2, "screenshot": "a.jpg"}], r"events\[0\]\.screenshot: expected a \.png"),
    ([{"frame": 2, "mouse": [1]}], r"events\[0\]\.mouse: expected \[x, y\]"),
])
def test_script_errors_name_the_event_and_field(events, message):
    with pytest.raises(OptionError, match=message):
        InputScript.parse({"events": events}, KEYS, "s.json")


def test_script_file_errors(tmp_path):
    with pytest.raises(OptionError, match="cannot read it"):
        InputScript.load(tmp_path / "missing.json", KEYS)
    (tmp_path / "bad.json").write_text("{\"events\": [")
    with pytest.raises(OptionError, match=r"bad.json: not valid JSON \(line 1"):
        InputScript.load(tmp_path / "bad.json", KEYS)
    with pytest.raises(OptionError, match="dt: expected seconds per frame > 0"):
        InputScript.parse({"dt": 0, "events": []}, KEYS)


# -- assignments and camera paths --------------------------------------------------------------------
def test_assignment_from_tune_result_and_plain_json(tmp_path):
    from rayvr.viewer.assignment import apply_assignment, load_assignment, save_assignment

    scene = rv.scenes.cornell_box()
    (tmp_path / "tune.json").write_text(json.dumps({"assignment": {"Floor": "REFLECTIONS", "TallBox": "PATH_TRACED"},
                                                    "budget_ms": 11.1}))
    got = load_assignment(tmp_path, scene)      # a tune report folder means its tune.json
    assert got == {"Floor": rv.Effect.REFLECTIONS, "TallBox": rv.Effect.PATH_TRACED}
    apply_assignment(scene, got)
    save_assignment(tmp_path / "mine.json", scene)
    saved = json.loads((tmp_path / "mine.json").read_text())
    assert saved["Floor"] == "reflections" and saved["TallBox"] == "path_traced" and saved["LeftWall"] == "shadows"
    assert load_assignment(tmp_path / "mine.json", scene)["Floor"] is rv.Effect.REFLECTIONS
    (tmp_path / "typo.json").write_text(json.dumps({"Flor": "raster"}))
    with pytest.raises(OptionError, match=r"typo.json: no material 'Flor' in scene 'cornell_box' \(did you mean 'Floor'"):
        load_assignment(tmp_path / "typo.json", scene)
    (tmp_path / "effect.json").write_text(json.dumps({"Floor": "shiny"}))
    with pytest.raises(OptionError, match="unknown effect 'shiny'"):
        load_assignment(tmp_path / "effect.json", scene)


def test_camera_path_round_trip_is_a_pose_log(tmp_path):
    path = CameraPath(ipd=0.07, fov_left=rv.xr.Fov.from_degrees(-50, 40, 45, -45),
                      fov_right=rv.xr.Fov.from_degrees(-40, 50, 45, -45), near=0.1, far=50.0)
    with pytest.raises(OptionError, match="no poses yet"):
        path.save(tmp_path / "empty.json")
    assert not (tmp_path / "empty.json").exists()
    for i in range(3):
        path.append(0.1 * i, Pose([i, 0.0, 0.0], orientation(0.1 * i, 0.0)))
    path.append(0.2, Pose([9, 9, 9]))          # a repeated time is nudged after the last
    path.save(tmp_path / "p.json")
    back = CameraPath.load(tmp_path / "p.json")
    assert len(back) == 4 and back.ipd == 0.07 and back.near == 0.1 and back.far == 50.0
    np.testing.assert_allclose(back.fov_left.degrees(), (-50, 40, 45, -45))
    np.testing.assert_allclose(back.poses[2].orientation, orientation(0.2, 0.0), atol=1e-12)
    assert back.times[3] > back.times[2]
    log = rv.xr.PoseLog(tmp_path / "p.json")    # SimulatedHeadset can play it in time
    np.testing.assert_allclose(log.pose_at(0.1).position, [1, 0, 0])
    base = default_views(rv.scenes.cornell_box(), 2, (32, 32))
    views = back.view_set(1, base)
    np.testing.assert_allclose(np.linalg.norm(views[1].pose.position - views[0].pose.position), 0.07)
    assert views[0].near == 0.1 and views[1].fov == back.fov_right
    doc = json.loads((tmp_path / "p.json").read_text())
    doc["fov_left"] = [-50, 40, 45]
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    with pytest.raises(XrError, match=r"bad.json: fov_left: expected \[left, right, up, down\]"):
        CameraPath.load(tmp_path / "bad.json")


def test_render_camera_path_options_fail_in_one_line(tmp_path, capsys):
    path = CameraPath()
    path.append(0.0, Pose())
    path.save(tmp_path / "p.json")
    assert main(["render", "--camera-path", str(tmp_path / "p.json"), "--views", "4"]) == 2
    assert "--camera-path replays 1 or 2 views" in capsys.readouterr().err
    assert main(["render", "--camera-path", str(tmp_path / "p.json"), "--frames", "3"]) == 2
    assert "leave out --frames" in capsys.readouterr().err
    assert main(["render", "--camera-path", str(tmp_path / "nope.json"), "--out", str(tmp_path / "o.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nope.json" in err and not list(tmp_path.glob("o*.png"))


def test_render_replays_a_camera_path_frame_per_pose(gpu, tmp_path, capsys):
    scene = rv.scenes.cornell_box()
    base = default_views(scene, 1, (16, 16))
    path = CameraPath()
    for i in range(3):
        path.append(i / 90, Pose(base[0].pose.position + [0.0, 0.0, -0.1 * i], base[0].pose.orientation))
    path.save(tmp_path / "p.json")
    code = main(["render", "--camera-path", str(tmp_path / "p.json"), "--views", "1", "--size", "16x16",
                 "--effect", "*=raster", "--exposure", "0", "--preset", "raw", "--out", str(tmp_path / "f.png")])
    assert code == 0, capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.glob("f_*.png")) == ["f_0000.png", "f_0001.png", "f_0002.png"]
    from PIL import Image

    with rv.Renderer(scene_raster(), rv.graphs.hybrid(preset="raw"), views=base) as r:
        r.render(path.view_set(0, base))
        r.render(path.view_set(1, base))
        expected = r.read_output(flip_y=True)[0][..., :3]
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "f_0001.png")), expected)


def scene_raster():
    scene = rv.scenes.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.RASTER
    return scene


# -- headless safety ----------------------------------------------------------------------------------
def test_import_rayvr_needs_no_display_and_no_viewer_extra():
    code = ("import sys, rayvr; rayvr.view; rayvr.viewer; import rayvr.cli.main as m; m.build_parser(); "
            "bad = [n for n in ('glfw', 'imgui_bundle') if n in sys.modules]; print(bad); assert not bad")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                         env={k: v for k, v in __import__("os").environ.items() if k != "DISPLAY"})
    assert out.returncode == 0, out.stdout + out.stderr


def test_view_without_a_display_exits_2_in_one_line(monkeypatch, capsys):
    pytest.importorskip("glfw")
    pytest.importorskip("imgui_bundle")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", "--frames", "1"]) == 2
    err = capsys.readouterr().err
    assert err == ("rayvr: error: rayvr view needs a display: DISPLAY is not set (run under Xvfb, or use "
                   "rayvr render)\n")


@pytest.mark.parametrize("module, name", [("glfw", "glfw"), ("imgui_bundle", "imgui-bundle")])
def test_view_without_the_extra_exits_2_in_one_line(monkeypatch, capsys, module, name):
    if module == "imgui_bundle":
        pytest.importorskip("glfw")                            # glfw is looked for first
    monkeypatch.setitem(sys.modules, module, None)             # importing it raises ImportError
    assert main(["view"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"needs the viewer extra ({name} is missing" in err
    assert "pip install 'rayvr[viewer]'" in err


def test_view_bad_options_exit_2_before_any_window(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    assert main(["view", "--screenshot", "a.png"]) == 2
    assert "--screenshot needs --frames N" in capsys.readouterr().err
    assert main(["view", "--frames", "2", "--screenshot", "a.jpg"]) == 2
    assert "write .png (the window) or .exr" in capsys.readouterr().err
    assert main(["view", "--size", "0x4"]) == 2
    assert "--size 0x4: expected WIDTHxHEIGHT" in capsys.readouterr().err
    assert main(["view", "--preset", "rift"]) == 2
    assert "unknown headset preset 'rift'" in capsys.readouterr().err
