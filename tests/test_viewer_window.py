"""`rayvr view` in a real window under Xvfb, driven by scripted input, checked on its screenshots.

The Cornell box, every material RASTER (direct light, no rays), 128x128 per view shown 2x in a
256x256 window (nearest texels, so every other window pixel is the view's pixel). Where a wall
edge lands is computed from the scene's own vertices and the recorded camera poses with
View.project, and compared with where the red and green pixels are.
"""
from __future__ import annotations

import json
import os
import select
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rayvr as rv
from rayvr.viewer.view_rig import ViewRig
from rayvr.xr.camera_path import CameraPath

SIZE = 128
DT = 0.1


@pytest.fixture(scope="module")
def display():
    """An Xvfb server on a free display number (Xvfb picks it: -displayfd); DISPLAY for it."""
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (apt-get install xvfb); the window tests need an X server")
    for module in ("glfw", "imgui_bundle"):
        pytest.importorskip(module, reason="the viewer extra is not installed: pip install 'rayvr[viewer]'")
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                            pass_fds=(write_fd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_fd)
    try:
        ready, _, _ = select.select([read_fd], [], [], 20)
        number = os.read(read_fd, 16).decode().strip() if ready else ""
        if not number.isdigit():
            pytest.fail("Xvfb did not report a display number within 20 s")
        yield f":{number}"
    finally:
        os.close(read_fd)
        proc.terminate()
        proc.wait(10)


def rayvr_cmd(args, display, cwd, timeout=180):
    env = {**os.environ, "DISPLAY": display}
    return subprocess.run([sys.executable, "-m", "rayvr", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)


def view_pixels(path) -> np.ndarray:
    """The 128x128 view from a 256x256 screenshot (float RGB, rows top-down)."""
    from PIL import Image

    return np.asarray(Image.open(path), dtype=np.float64)[::2, ::2, :3]


def red(img):
    return (img[..., 0] > 1.8 * img[..., 1]) & (img[..., 0] > 12)


def green(img):
    return (img[..., 1] > 1.5 * img[..., 0]) & (img[..., 1] > 12)


def wall_back_edge(scene, name, y):
    """The world point at height y on the back vertical edge of wall `name` (from its vertices)."""
    inst = next(i for i in scene.instances if i.name == name)
    p = scene.meshes[inst.mesh].positions.astype(np.float64)
    back = p[np.argsort(p[:, 2])[:2]]
    back = back[np.argsort(back[:, 1])]
    t = (y - back[0, 1]) / (back[1, 1] - back[0, 1])
    return back[0] + t * (back[1] - back[0])


SCRIPT = {"dt": DT, "events": [
    {"frame": 0, "key": "H", "action": "tap"},          # hide the panels for the geometry shots
    {"frame": 2, "screenshot": "a.png"},
    {"frame": 3, "screenshot": "a_again.png"},
    {"frame": 4, "effect": {"LeftWall": "path_traced"}},
    {"frame": 4, "screenshot": "left_wall_pt.png"},
    {"frame": 5, "effect": {"LeftWall": "raster"}},
    {"frame": 6, "key": "W", "action": "down"},         # forward for frames 6..10
    {"frame": 11, "key": "W", "action": "up"},
    {"frame": 11, "screenshot": "forward.png"},
    {"frame": 12, "key": "D", "action": "down"},        # strafe right for frames 12, 13
    {"frame": 14, "key": "D", "action": "up"},
    {"frame": 14, "screenshot": "strafed.png"},
    {"frame": 15, "mouse": [128, 128]},                # drag 20 px right with the right button
    {"frame": 15, "button": "right", "action": "down"},
    {"frame": 16, "mouse": [148, 128]},
    {"frame": 17, "button": "right", "action": "up"},
    {"frame": 18, "quit": True}]}


@pytest.fixture(scope="module")
def scripted(display, tmp_path_factory):
    """One scripted viewer run: its folder, its recorded camera path, the scene and its views."""
    folder = tmp_path_factory.mktemp("view")
    (folder / "script.json").write_text(json.dumps(SCRIPT))
    rv.graphs.hybrid(preset="raw").save(folder / "raw.json")   # each frame alone: the replay's pixels exactly
    out = rayvr_cmd(["view", "--views", "1", "--size", f"{SIZE}x{SIZE}", "--window", "256x256", "--effect", "*=raster",
                     "--graph", "raw.json", "--script", "script.json", "--record", "path.json"], display, folder)
    assert out.returncode == 0, out.stderr
    scene = rv.scenes.cornell_box()
    rig = ViewRig.from_scene(scene, 1, (SIZE, SIZE))
    return folder, CameraPath.load(folder / "path.json"), scene, rig


def edge_columns(scripted, shot, frame, y=0.4):
    """(expected, measured) x of the red wall's and the green wall's inner edges on the image row
    that sees height y on the back wall; expected from the geometry and frame's recorded pose."""
    folder, path, scene, rig = scripted
    img = view_pixels(folder / shot)
    v = rig.view_set(path.poses[frame])[0]
    left, right = v.project(wall_back_edge(scene, "LeftWall", y)), v.project(wall_back_edge(scene, "RightWall", y))
    row = SIZE - 1 - int(np.floor(left[1]))
    reds, greens = np.nonzero(red(img[row]))[0], np.nonzero(green(img[row]))[0]
    return (left[0], right[0]), (reds.max() + 1, greens.min()), row


def test_scene_is_drawn_where_the_geometry_says(scripted):
    folder, path, scene, rig = scripted
    img = view_pixels(folder / "a.png")
    (xl, xr), (ml, mr), row = edge_columns(scripted, "a.png", 2)
    assert abs(ml - xl) <= 1.5 and abs(mr - xr) <= 1.5
    # the red wall fills the columns left of its edge, the green one those right of its edge
    band = img[row - 3:row + 4]
    assert red(band[:, :int(xl) - 2]).mean() > 0.9
    assert green(band[:, int(xr) + 2:]).mean() > 0.9
    assert not red(band[:, int(xl) + 2:int(xr) - 2]).any() and not green(band[:, int(xl) + 2:int(xr) - 2]).any()
    # the display's clear colour shows nowhere: the frame fills the window
    from rayvr.viewer.display import BACKGROUND

    clear = np.round(np.array(BACKGROUND) * 255)
    assert not np.all(np.abs(img - clear) <= 1, axis=-1).any()


def test_forward_key_moves_camera_and_back_wall_grows(scripted):
    folder, path, scene, rig = scripted
    lo, hi = scene.bounds()
    speed = 0.5 * np.linalg.norm(hi - lo)                  # the viewer's default speed
    moved = path.poses[10].position - path.poses[5].position   # W held for frames 6..10
    np.testing.assert_allclose(moved, [0.0, 0.0, -5 * DT * speed], atol=1e-9)
    (xl0, xr0), (ml0, mr0), _ = edge_columns(scripted, "a.png", 2)
    (xl1, xr1), (ml1, mr1), _ = edge_columns(scripted, "forward.png", 11)
    assert abs(ml1 - xl1) <= 1.5 and abs(mr1 - xr1) <= 1.5
    assert ml1 < ml0 - 5 and mr1 > mr0 + 5                 # the back wall spans more columns


def test_strafe_key_shifts_the_walls_left(scripted):
    folder, path, scene, rig = scripted
    moved = path.poses[13].position - path.poses[11].position   # D held for frames 12, 13
    assert moved[0] > 0 and abs(moved[1]) < 1e-9 and abs(moved[2]) < 1e-9
    (xl0, xr0), (ml0, mr0), _ = edge_columns(scripted, "forward.png", 11)
    (xl1, xr1), (ml1, mr1), _ = edge_columns(scripted, "strafed.png", 14)
    assert abs(ml1 - xl1) <= 1.5 and abs(mr1 - xr1) <= 1.5
    assert ml1 < ml0 - 5 and mr1 < mr0 - 5


def test_mouse_drag_turns_the_camera(scripted):
    from rayvr.viewer.camera import LOOK_RADIANS_PER_PIXEL, yaw_pitch

    folder, path, scene, rig = scripted
    (yaw0, pitch0), (yaw1, pitch1) = yaw_pitch(path.poses[15]), yaw_pitch(path.poses[16])
    assert yaw1 - yaw0 == pytest.approx(-20 * LOOK_RADIANS_PER_PIXEL) and pitch1 == pytest.approx(pitch0)
    np.testing.assert_allclose(path.poses[16].position, path.poses[15].position)


def test_switching_a_material_effect_changes_its_pixels(scripted):
    folder, path, scene, rig = scripted
    before, again, after = (view_pixels(folder / n) for n in ("a.png", "a_again.png", "left_wall_pt.png"))
    assert np.allclose(path.poses[4].position, path.poses[2].position)
    (xl, xr), _, row = edge_columns(scripted, "a.png", 2)
    rows = slice(row - 10, row + 30)
    left, right = (rows, slice(0, int(xl) - 1)), (rows, slice(int(xr) + 2, SIZE))
    # RASTER -> PATH_TRACED adds the light bounced off the other walls to the red wall
    assert after[left][..., 0].mean() > before[left][..., 0].mean() + 5
    assert abs(again[left][..., 0].mean() - before[left][..., 0].mean()) < 2    # frame-to-frame noise only
    assert np.abs(after[right].mean((0, 1)) - before[right].mean((0, 1))).max() < 2   # RightWall stays RASTER


def test_recorded_camera_path_replays_in_rayvr_render(scripted, display):
    folder, path, scene, rig = scripted
    out = rayvr_cmd(["render", "--camera-path", "path.json", "--views", "1", "--size", f"{SIZE}x{SIZE}", "--effect",
                     "*=raster", "--exposure", "0", "--preset", "raw", "--out", "replay/r.png"], display, folder)
    assert out.returncode == 0, out.stderr
    assert len(list((folder / "replay").glob("r_*.png"))) == len(path) == 19
    for shot, frame in (("a.png", 2), ("forward.png", 11), ("strafed.png", 14)):
        replay = view_pixels_1x(folder / "replay" / f"r_{frame:04d}.png")
        np.testing.assert_array_equal(view_pixels(folder / shot), replay)


def view_pixels_1x(path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path), dtype=np.float64)[..., :3]


def test_ui_is_drawn_over_the_frame_and_only_there(display, tmp_path):
    """With --target-frames 1 the frame stops changing once rendered, so screenshots with and
    without the panels differ exactly where the panel window is."""
    script = {"events": [{"frame": 2, "key": "H", "action": "tap"}, {"frame": 4, "screenshot": "no_ui.png"},
                         {"frame": 5, "key": "H", "action": "tap"}, {"frame": 6, "screenshot": "ui.png"},
                         # a drag that starts on the panel is the panel's; one beside it turns the camera
                         {"frame": 7, "mouse": [60, 120]}, {"frame": 8, "button": "left", "action": "down"},
                         {"frame": 9, "mouse": [90, 120]}, {"frame": 10, "button": "left", "action": "up"},
                         {"frame": 11, "mouse": [252, 120]}, {"frame": 12, "button": "left", "action": "down"},
                         {"frame": 13, "mouse": [232, 120]}, {"frame": 14, "button": "left", "action": "up"},
                         {"frame": 15, "quit": True}]}
    (tmp_path / "s.json").write_text(json.dumps(script))
    out = rayvr_cmd(["view", "--views", "1", "--size", "128x128", "--window", "256x256", "--effect", "*=raster",
                     "--target-frames", "1", "--script", "s.json", "--record", "p.json"], display, tmp_path)
    assert out.returncode == 0, out.stderr
    from rayvr.viewer.camera import yaw_pitch

    yaws = [yaw_pitch(p)[0] for p in CameraPath.load(tmp_path / "p.json").poses]
    assert yaws[10] == yaws[0]
    assert yaws[13] > yaws[12] + 0.05                          # dragged left: turned left
    from PIL import Image

    ui, no_ui = (np.asarray(Image.open(tmp_path / n), dtype=np.int32) for n in ("ui.png", "no_ui.png"))
    from rayvr.viewer.panels import WINDOW_POS, WINDOW_WIDTH

    x0, y0 = (int(c) for c in WINDOW_POS)
    x1 = x0 + int(min(WINDOW_WIDTH, 256 - 16))
    differs = np.abs(ui - no_ui).sum(-1) > 0
    assert differs[y0:y0 + 20, x0:x1].mean() > 0.9           # the title bar covers the scene
    outside = np.ones_like(differs)
    outside[y0:256 - 8, x0:x1] = False
    assert not differs[outside].any()
    # the focused window's title bar in ImGui's dark theme: TitleBgActive (0.16, 0.29, 0.48)
    title = ui[y0 + 4:y0 + 14, x0 + 120:x1 - 40].reshape(-1, 3)
    np.testing.assert_allclose(np.median(title, axis=0), [41, 74, 122], atol=3)


def test_stereo_side_by_side_and_screenshot_option(display, tmp_path):
    """--views 2: the window shows both eyes side by side; the right eye, 63 mm to the right,
    sees the red wall's edge further left, as its own projection says."""
    out = rayvr_cmd(["view", "--views", "2", "--size", "64x64", "--effect", "*=raster", "--no-ui",
                     "--frames", "3", "--screenshot", "stereo.png"], display, tmp_path)
    assert out.returncode == 0, out.stderr
    assert "wrote stereo.png" in out.stdout
    from PIL import Image

    img = np.asarray(Image.open(tmp_path / "stereo.png"), dtype=np.float64)[..., :3]
    assert img.shape == (64, 128, 3)
    scene = rv.scenes.cornell_box()
    rig = ViewRig.from_scene(scene, 2, (64, 64))
    from rayvr.xr.cameras import camera_pose

    views = rig.view_set(camera_pose(scene)[0])
    for eye, view in enumerate(views):
        half = img[:, eye * 64:(eye + 1) * 64]
        edge = view.project(wall_back_edge(scene, "LeftWall", 0.4))
        row = 63 - int(np.floor(edge[1]))
        reds = np.nonzero(red(half[row]))[0]
        assert abs(reds.max() + 1 - edge[0]) <= 1.5, (eye, reds.max() + 1, edge[0])
    left_edge, right_edge = (v.project(wall_back_edge(scene, "LeftWall", 0.4))[0] for v in views)
    assert right_edge < left_edge - 1


def test_python_hook_presets_properties_and_saves(display, tmp_path):
    """rv.view(..., on_frame=hook) in a script: a headset preset changes the views' size and fov at
    the next frame, a ToneMap exposure edit recompiles and brightens the frame, the graph, the
    effects and the HDR output are written, and an error-overlay hook's map is drawn over the views."""
    code = r'''
import json, numpy as np, rayvr as rv
scene = rv.scenes.cornell_box()
for m in scene.materials:
    m.effect = rv.Effect.RASTER
graph = rv.graphs.hybrid(preset="raw")
log = []
def hook(v):
    i = v.frame_index
    log.append({"frame": i, "size": list(v.renderer.size), "views": v.renderer.view_count,
                "fov": list(v.rig.fov_left.degrees()), "compiles": v.renderer.compiles,
                "window": float(v.read_window().mean()), "output": float(v.renderer.read_output()[..., :3].mean())})
    if i == 1:
        v.set_preset("index", 0.05)
    if i == 3:
        v.show_ui = False
    if i == 4:
        v.set_pass_property("ToneMap", "exposure", 2.0)
    if i == 6:
        v.set_effect("Floor", "reflections")
        v.save_graph("g.json"); v.save_effects("effects.json"); v.request_screenshot("hdr.exr")
    if i == 7:      # the error-overlay hook: an opaque magenta map over both views
        w, h = v.renderer.size
        magenta = np.tile(np.array([255, 0, 255, 255], np.uint8), (2, h, w, 1))
        tex = v.gpu.gl.texture_array((w, h, 2), 4, magenta.tobytes())
        v.error_overlay, v.overlay_alpha = (lambda viewer: tex), 1.0
    if i == 8:
        window = v.read_window()
        log[-1]["centre"] = window[window.shape[0] // 2, window.shape[1] // 2].tolist()
        log[-1]["corner"] = window[0, 0].tolist()
    return i < 8
n = rv.view(scene, graph, views=1, size=(64, 64), on_frame=hook)
print(json.dumps({"frames": n, "log": log, "exposure": graph.get_pass("ToneMap").exposure,
                  "floor": scene.materials["Floor"].effect.name}))
'''
    env = {**os.environ, "DISPLAY": display}
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=180)
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout.strip().splitlines()[-1])
    log = {e["frame"]: e for e in doc["log"]}
    assert doc["frames"] == 9
    assert log[1]["size"] == [64, 64] and log[1]["views"] == 1
    assert log[2]["size"] == [72, 80] and log[2]["views"] == 2          # index: 1440x1600 x 0.05, stereo
    index = rv.xr.get_preset("index")
    np.testing.assert_allclose(log[2]["fov"], index.left_fov.degrees())
    assert log[5]["compiles"] == log[4]["compiles"] + 1                 # the property edit recompiled
    assert log[5]["output"] > 1.5 * log[4]["output"]                   # two stops brighter
    assert log[5]["window"] > log[4]["window"]                          # and so is the window
    assert doc["exposure"] == 2.0 and doc["floor"] == "REFLECTIONS"     # the caller's objects changed
    assert log[8]["centre"] == [255, 0, 255]                            # the overlay covers the image
    assert log[8]["corner"] != [255, 0, 255]                            # ... and not the letterbox
    saved = rv.RenderGraph.load(tmp_path / "g.json")
    assert saved.get_pass("ToneMap").exposure == 2.0
    effects = json.loads((tmp_path / "effects.json").read_text())
    assert effects["Floor"] == "reflections" and effects["LeftWall"] == "raster"
    import OpenEXR

    with OpenEXR.File(str(tmp_path / "hdr.exr")) as f:
        rgb = f.channels()["RGB"].pixels
    assert rgb.shape == (80, 144, 3) and np.isfinite(rgb).all() and rgb.max() > 0.1


def test_bad_script_exits_2_with_one_line(display, tmp_path):
    (tmp_path / "s.json").write_text(json.dumps({"events": [{"frame": 1, "key": "WW"}]}))
    out = rayvr_cmd(["view", "--script", "s.json", "--frames", "2"], display, tmp_path)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "events[0].key" in lines[0] and "'WW'" in lines[0] and "s.json" in lines[0]
    assert not list(Path(tmp_path).glob("*.png"))


def test_headless_rendering_continues_after_a_window_in_the_same_process(display, tmp_path):
    """A notebook renders headless (EGL), opens rv.view (GLX: the EGL context steps aside, as
    GLVND allows one current context per thread), closes it, and renders headless again: the
    same pixels before and after."""
    code = r'''
import numpy as np, rayvr as rv
scene = rv.scenes.cornell_box()
for m in scene.materials:
    m.effect = rv.Effect.RASTER
def frame():
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=1, size=(32, 32)) as r:
        r.render()
        return r.read_output()
before = frame()
assert rv.view(scene, views=1, size=(32, 32), frames=2) == 2
after = frame()
print(int(np.abs(before.astype(int) - after).max()), rv.gpu.get_context().caps.renderer)
'''
    env = {**os.environ, "DISPLAY": display}
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=180)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[0] == "0"
