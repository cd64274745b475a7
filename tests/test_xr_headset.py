"""SimulatedHeadset: compositor accounting, trajectories, pose logs, recording, sinks."""
import json
import math

import numpy as np
import pytest

from rayvr.errors import OptionError, XrError
from rayvr.xr import (Compositor, Fov, OffscreenViews, Pose, SimulatedHeadset, make_trajectory, mono_view,
                      quaternion)


def _run(headset, render_times_ms):
    headset.open(None)
    requests = []
    for ms in render_times_ms:
        r = headset.wait_frame()
        r.render_time_s = ms / 1000
        headset.submit(None, r)
        requests.append(r)
    return requests


def test_compositor_counts_on_time_reprojected_dropped_and_repeated_vsyncs():
    c = Compositor(100.0, max_late_vsyncs=1)
    statuses = []
    for ms in (5, 5, 15, 25, 5, 8):
        t = c.begin_frame()
        statuses.append((t.start_time, t.predicted_display_time, c.end_frame(t, ms / 1000).status))
    assert [s[2] for s in statuses] == ["on_time", "on_time", "reprojected", "dropped", "on_time", "on_time"]
    starts = [round(s[0] * 1000, 6) for s in statuses]
    assert starts == [0, 10, 20, 40, 70, 80]             # each frame starts at the vsync after the last finished
    assert [round(s[1] * 1000, 6) for s in statuses] == [10, 20, 30, 50, 80, 90]
    s = c.stats()
    assert (s["frames"], s["on_time"], s["reprojected"], s["dropped"]) == (6, 4, 1, 1)
    assert s["vsyncs"] == 9 and s["repeated_vsyncs"] == 4   # shown at vsyncs 1, 2, 4, 8, 9
    assert s["motion_to_photon_ms"]["mean"] == pytest.approx((4 * 10 + 20) / 5)
    assert s["motion_to_photon_ms"]["max"] == pytest.approx(20)
    assert s["frame_time_ms"]["max"] == pytest.approx(25)


def test_drop_policy_drops_every_late_frame_and_exact_vsync_is_on_time():
    c = Compositor(50.0, late_policy="drop")
    for ms in (20, 21, 1):
        c.end_frame(c.begin_frame(), ms / 1000)
    assert [f.status for f in c.frames] == ["on_time", "dropped", "on_time"]
    with pytest.raises(OptionError, match="late_policy"):
        Compositor(90, late_policy="skip")


def test_simulated_headset_uses_render_time_and_preset_refresh():
    h = SimulatedHeadset("quest2", size=(16, 16))
    assert h.refresh_hz == 90.0 and h.size == (16, 16) and h.view_count == 2
    _run(h, [5, 5, 20, 5])
    s = h.stats()
    assert (s["on_time"], s["reprojected"], s["dropped"]) == (3, 1, 0)
    assert s["preset"] == "quest2" and s["refresh_hz"] == 90.0


def test_fixed_frame_time_and_frame_limit_end_the_session():
    h = SimulatedHeadset("index", refresh_hz=144, size=(8, 8), frames=3, frame_time_s=0.001)
    h.open(None)
    n = 0
    while (r := h.wait_frame()) is not None:
        h.submit(None, r)
        n += 1
    assert n == 3 and h.stats()["on_time"] == 3
    assert r is None
    with pytest.raises(XrError, match="submit each request once"):
        h2 = SimulatedHeadset(size=(8, 8))
        req = h2.wait_frame()
        h2.submit(None, req)
        h2.submit(None, req)


def test_trajectories_are_deterministic():
    def packs(traj):
        h = SimulatedHeadset("vive_pro2", size=(8, 8), trajectory=traj, frame_time_s=0.004)
        out = []
        for _ in range(5):
            r = h.wait_frame()
            out.append(r.views.pack())
            h.submit(None, r)
        return out

    for traj in ("still", "turn", "walk"):
        assert packs(traj) == packs(traj)
    assert packs("turn") != packs("still")


def test_turn_and_walk_follow_their_formulas():
    start = Pose([1.0, 1.6, 2.0])
    turn = make_trajectory("turn", start)
    yaw = quaternion.from_axis_angle([0, 1, 0], math.radians(45))
    assert np.allclose(turn.pose_at(1.0).orientation, yaw)   # a quarter of the 4 s period: +amplitude
    walk = make_trajectory("walk", start)
    assert np.allclose(walk.pose_at(2.0).position, [1.0, 1.6 + 0.02 * math.sin(2 * math.pi * 3.6), 2.0 - 2.8])
    with pytest.raises(OptionError, match="did you mean 'walk'"):
        make_trajectory("wakl", start)


def test_headset_poses_come_from_the_trajectory_at_display_time():
    h = SimulatedHeadset("index", size=(8, 8), trajectory="walk", frame_time_s=0.001)
    r = h.wait_frame()
    expected = make_trajectory("walk", h.start_pose).pose_at(r.predicted_display_time)
    assert np.allclose(r.head_pose.position, expected.position)
    mid = (r.views[0].pose.position + r.views[1].pose.position) / 2
    assert np.allclose(mid, expected.position)
    assert np.linalg.norm(r.views[1].pose.position - r.views[0].pose.position) == pytest.approx(h.ipd)


def _write_log(tmp_path, doc, name="poses.json"):
    path = tmp_path / name
    path.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    return path


def test_pose_log_interpolates_and_clamps(tmp_path):
    q90 = quaternion.from_axis_angle([0, 1, 0], math.pi / 2)
    path = _write_log(tmp_path, {"poses": [
        {"t": 0.0, "position": [0, 1.5, 0], "orientation": [0, 0, 0, 1]},
        {"t": 1.0, "position": [2, 1.5, -4], "orientation": list(q90)}]})
    h = SimulatedHeadset("index", size=(8, 8), trajectory=str(path))
    log = h.trajectory
    mid = log.pose_at(0.5)
    assert np.allclose(mid.position, [1, 1.5, -2])
    assert np.allclose(mid.orientation, quaternion.from_axis_angle([0, 1, 0], math.pi / 4))
    assert np.allclose(log.pose_at(-1).position, [0, 1.5, 0])
    assert np.allclose(log.pose_at(9).orientation, q90)


@pytest.mark.parametrize("doc, message", [
    ({"poses": [{"t": 0, "position": [0, 0, 0]}]}, r"poses\[0\]\.orientation: missing"),
    ({"poses": [{"t": 0, "position": [0, 0], "orientation": [0, 0, 0, 1]}]}, r"poses\[0\]\.position: expected 3"),
    ([{"t": 0, "position": [0, 0, 0], "orientation": [0, 0, 0, 1]},
      {"t": 0, "position": [0, 0, 0], "orientation": [0, 0, 0, 1]}], r"poses\[1\]\.t: times must increase"),
    ({"poses": [{"t": "a", "position": [0, 0, 0], "orientation": [0, 0, 0, 1]}]}, r"poses\[0\]\.t: expected a time"),
    ({"poses": [{"t": 0, "position": [0, 0, 0], "orientation": [0, 0, 0, 0]}]}, r"poses\[0\]\.orientation: a zero"),
    ({"frames": []}, "poses: expected a non-empty list"),
    ("{not json", "not valid JSON"),
])
def test_pose_log_errors_name_the_file_and_field(tmp_path, doc, message):
    path = _write_log(tmp_path, doc)
    with pytest.raises(XrError, match=message) as info:
        make_trajectory(str(path), Pose())
    assert str(path) in str(info.value)


def test_missing_pose_log_names_the_file(tmp_path):
    with pytest.raises(XrError, match="cannot read the pose log"):
        make_trajectory(str(tmp_path / "nope.json"), Pose())


def test_unknown_preset_lists_the_known_ones():
    with pytest.raises(OptionError, match=r"did you mean 'index'.*quest3"):
        SimulatedHeadset("indx")


def _eyes_texture(gl, w, h, shade=0):
    data = np.zeros((2, h, w, 4), np.uint8)
    data[..., 1:3] = shade
    data[0, ..., 0] = 200                                  # left eye red
    data[1, ..., 1] = 200                                  # right eye green
    data[:, :, :, 2] = (np.arange(h) * 10)[None, :, None]  # blue = GL row index (row 0 at the bottom)
    data[..., 3] = 255
    return gl.texture_array((w, h, 2), 4, data.tobytes())


def test_recording_writes_eyes_side_by_side_and_gif(gl, tmp_path):
    from PIL import Image

    w, h = 8, 6
    textures = [_eyes_texture(gl, w, h, shade=s) for s in (0, 60)]
    hs = SimulatedHeadset("index", size=(w, h), record_dir=tmp_path, video="gif", frames=2, frame_time_s=0.001)
    hs.open(None)
    while (r := hs.wait_frame()) is not None:
        hs.submit(textures[r.index], r)
    hs.close()
    left = np.array(Image.open(tmp_path / "frame_00000_left.png"))
    right = np.array(Image.open(tmp_path / "frame_00000_right.png"))
    sbs = np.array(Image.open(tmp_path / "frame_00000_sbs.png"))
    assert left.shape == (h, w, 4) and sbs.shape == (h, 2 * w, 4)
    assert (left[..., 0] == 200).all() and (right[..., 1] == 200).all()
    assert left[0, 0, 2] == (h - 1) * 10 and left[-1, 0, 2] == 0   # image top = GL's top row
    assert (sbs[:, :w, 0] == 200).all() and (sbs[:, w:, 1] == 200).all()
    gif = Image.open(hs.video_path)
    assert hs.video_path.suffix == ".gif" and gif.n_frames == 2


def test_submit_checks_size_and_view_count(gl):
    hs = SimulatedHeadset("index", size=(8, 6))
    r = hs.wait_frame()
    with pytest.raises(XrError, match=r"expected a texture array of 8x6 with 2 layers, got 4x6 with 2"):
        hs.submit(gl.texture_array((4, 6, 2), 4), r)


def test_offscreen_views_runs_its_frames_and_reads_back(gl):
    vs = mono_view(Pose(), Fov.symmetric(60, 1), (8, 6))
    sink = OffscreenViews(vs, frames=2)
    sink.open(None)
    tex = gl.texture_array((8, 6, 1), 4, np.full((1, 6, 8, 4), 77, np.uint8).tobytes())
    seen = 0
    while (r := sink.wait_frame()) is not None:
        assert r.views is vs
        sink.submit(tex, r)
        seen += 1
    assert seen == 2 and sink.submitted == 2
    assert (sink.read() == 77).all() and sink.read().shape == (1, 6, 8, 4)


def test_place_restarts_the_trajectory_at_a_pose():
    h = SimulatedHeadset("index", size=(8, 8), trajectory="walk")
    assert not h.start_pose_given
    h.place(Pose([5.0, 2.0, 1.0]))
    r = h.wait_frame()
    mid = (r.views[0].pose.position + r.views[1].pose.position) / 2
    assert h.start_pose_given and mid[0] == pytest.approx(5.0) and mid[2] < 1.0
