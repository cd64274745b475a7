"""View math: stereo registration for every preset, packing, the GLSL side, camera grids."""
import math
import struct

import numpy as np
import pytest

from rayvr.errors import OptionError, XrError
from rayvr.xr import (PRESETS, Fov, Pose, View, ViewSet, camera_grid, lightfield_row, look_at, mono_view,
                      stereo_views)
from rayvr.xr import quaternion
from rayvr.xr.views import FLAG_REVERSED_Z, HEADER_BYTES, VIEW_STRUCT_FLOATS

# A head far from the world origin, turned and tilted: registration must not depend on either.
HEAD = Pose([1234.5, 1.7, -987.25],
            quaternion.multiply(quaternion.from_axis_angle([0, 1, 0], math.radians(30)),
                                quaternion.from_axis_angle([1, 0, 0], math.radians(-10))))


def _ahead(pose: Pose, distance: float) -> np.ndarray:
    return pose.transform_point([0.0, 0.0, -distance])


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_stereo_disparity_is_ipd_f_over_d_for_every_preset(name):
    p = PRESETS[name]
    views = stereo_views(HEAD, p.ipd, p.left_fov, p.right_fov, p.eye_size)
    w = p.eye_size[0]
    # focal length in pixels straight from the angles, independent of rayvr's helpers
    f = w / (math.tan(p.left_fov.angle_right) - math.tan(p.left_fov.angle_left))
    far = [v.project(_ahead(HEAD, 1e9)) for v in views]
    for d in (0.5, 1.0, 2.0, 10.0):
        left, right = (v.project(_ahead(HEAD, d)) for v in views)
        disparity = (left[0] - right[0]) - (far[0][0] - far[1][0])
        assert abs(disparity - p.ipd * f / d) < 0.5, (name, d, disparity, p.ipd * f / d)
        assert abs(left[1] - right[1]) < 1e-6   # no vertical disparity


def test_point_at_infinity_lands_on_the_same_pixel_with_symmetric_fovs():
    fov = Fov.symmetric(90.0, 1.0)
    left, right = stereo_views(HEAD, 0.064, fov, fov, (128, 128))
    target = _ahead(HEAD, 1e12) + HEAD.rotation_matrix() @ np.array([3e11, -1e11, 0.0])
    a, b = left.project(target), right.project(target)
    assert np.allclose(a[:2], b[:2], atol=1e-3)


def test_eyes_are_ipd_apart_along_the_head_x_axis():
    left, right = stereo_views(HEAD, 0.07, Fov.symmetric(90, 1), Fov.symmetric(90, 1), (8, 8))
    delta = right.pose.position - left.pose.position
    assert np.allclose(delta, HEAD.rotation_matrix()[:, 0] * 0.07)
    assert np.allclose(left.pose.orientation, HEAD.orientation)


def test_mono_and_view_zero_agree():
    fov = Fov.from_degrees(-45, 40, 42, -47)
    pose = look_at([3, 2, 5], [0, 1, 0])
    mono = mono_view(pose, fov, (64, 48))
    grid = camera_grid(1, 1, 0.1, fov, (64, 48), center_pose=pose)
    stereo0 = stereo_views(pose, 0.0, fov, fov, (64, 48))
    for vs in (grid, stereo0):
        assert np.allclose(vs.matrices()["view_proj"][0], mono.matrices()["view_proj"][0], atol=1e-12)
        assert vs.pack() == mono.pack() if len(vs) == 1 else True
    assert grid.pack() == mono.pack()


def test_look_at_points_minus_z_at_the_target():
    pose = look_at([1, 2, 3], [4, 2, -1])
    forward = -pose.rotation_matrix()[:, 2]
    assert np.allclose(forward, np.array([3, 0, -4]) / 5)
    assert np.allclose(pose.rotation_matrix()[:, 1], [0, 1, 0])
    with pytest.raises(OptionError, match="parallel"):
        look_at([0, 0, 0], [0, 5, 0])


def test_projection_and_primary_ray_agree():
    v = View(look_at([0.3, 1.2, 2.0], [0, 1, 0]), Fov.from_degrees(-50, 40, 45, -35), 96, 64)
    for pixel in [(0.5, 0.5), (48.0, 32.0), (95.5, 10.25)]:
        o, d = v.primary_ray(pixel)
        hit = o + 3.7 * d
        assert np.allclose(v.project(hit)[:2], pixel, atol=1e-9)


def test_reversed_z_maps_near_to_one_and_infinity_to_zero():
    v = View(Pose(), Fov.symmetric(90, 1), 8, 8, near=0.1, reversed_z=True)
    assert v.project([0, 0, -0.1])[2] == pytest.approx(1.0)
    assert v.project([0, 0, -1e9])[2] == pytest.approx(0.0, abs=1e-9)
    header = struct.unpack("4I", ViewSet([v]).pack()[:16])
    assert header[3] & FLAG_REVERSED_Z


def _unpack(data: bytes):
    header = np.frombuffer(data[:HEADER_BYTES], dtype=np.uint32)
    body = np.frombuffer(data[HEADER_BYTES:], dtype=np.float32).reshape(header[0], VIEW_STRUCT_FLOATS)
    mats = body[:, :80].reshape(-1, 5, 4, 4).transpose(0, 1, 3, 2)   # column-major -> row-major
    return header, mats, body[:, 80:]


def test_packed_ssbo_matches_the_numpy_matrices_in_render_space():
    p = PRESETS["quest2"]
    vs = stereo_views(HEAD, p.ipd, p.left_fov, p.right_fov, (64, 64))
    origin = vs.origin()
    header, mats, rest = _unpack(vs.pack(frame_index=7, sample_index=3, jitter=(0.25, -0.5)))
    assert list(header) == [2, 7, 3, 0]
    m = vs.matrices(origin)
    for i, v in enumerate(vs):
        assert np.allclose(mats[i, 0], v.view_matrix(origin), atol=1e-5)
        assert np.allclose(mats[i, 1], v.projection_matrix(), atol=1e-5)
        assert np.allclose(mats[i, 2], m["view_proj"][i], atol=1e-5)
        assert np.allclose(mats[i, 3], v.inverse_view_matrix(origin), atol=1e-5)
        assert np.allclose(mats[i, 4], m["view_proj"][i], atol=1e-5)   # no history yet: prev = current
        assert np.allclose(rest[i, :3], v.pose.position - origin, atol=1e-5)
        assert np.allclose(rest[i, 4:8], v.fov.tangents(), atol=1e-6)
        assert np.allclose(rest[i, 8:12], [v.near, v.far, 64, 64])
        assert np.allclose(rest[i, 12:14], [0.25, -0.5])
    # camera-relative: the eyes sit +-IPD/2 around the render-space origin, not 1e3 m away
    assert np.abs(rest[:, :3]).max() < p.ipd


def test_prev_view_proj_follows_the_previous_frame():
    fov = Fov.symmetric(90, 1)
    a = stereo_views(Pose([0, 1.6, 0]), 0.064, fov, fov, (8, 8))
    a.pack()
    b = ViewSet(stereo_views(Pose([0.1, 1.6, 0]), 0.064, fov, fov, (8, 8)).views, previous=a)
    _, mats, _ = _unpack(b.pack())
    point_world = np.array([0.3, 1.4, -2.0, 1.0])
    pb = point_world.copy()
    pb[:3] -= b.origin()
    pa = point_world.copy()
    pa[:3] -= a.origin()
    # last frame's clip position of the same world point, computed from this frame's render space
    assert np.allclose(mats[0, 4].astype(np.float64) @ pb, a.matrices()["view_proj"][0] @ pa, atol=1e-4)


def test_views_of_different_sizes_are_rejected():
    fov = Fov.symmetric(90, 1)
    with pytest.raises(XrError, match="sizes differ"):
        ViewSet([View(Pose(), fov, 8, 8), View(Pose(), fov, 16, 8)])


def test_camera_grid_positions_order_and_spacing():
    center = look_at([0, 1, 3], [0, 1, 0])
    vs = camera_grid(4, 3, (0.1, 0.2), Fov.symmetric(40, 1), (16, 16), center_pose=center)
    assert len(vs) == 12
    local = np.array([np.linalg.inv(center.matrix()) @ [*v.pose.position, 1] for v in vs])[:, :3]
    assert np.allclose(local[0], [-0.15, -0.2, 0])       # view 0: left, bottom
    assert np.allclose(local[3], [0.15, -0.2, 0])        # end of the first row: right
    assert np.allclose(local[11], [0.15, 0.2, 0])        # last: right, top
    assert np.allclose(np.diff(local[:4, 0]), 0.1)
    assert all(np.allclose(v.pose.orientation, center.orientation) for v in vs)
    assert all(v.fov == vs[0].fov for v in vs)           # parallel, unsheared


def test_sheared_grid_converges_on_the_focal_plane():
    center = look_at([0, 1, 3], [0, 1, 0])
    focal = 2.5
    vs = camera_grid(5, 2, 0.05, Fov.symmetric(30, 0.75), (48, 64), center_pose=center, focal_distance=focal)
    on_plane = center.transform_point([0.2, -0.1, -focal])
    off_plane = center.transform_point([0.2, -0.1, -2 * focal])
    px = np.array([v.project(on_plane)[:2] for v in vs])
    assert np.allclose(px, px[0], atol=1e-6)
    spread = np.array([v.project(off_plane)[:2] for v in vs])
    assert np.ptp(spread[:, 0]) > 1.0                    # parallax behind the focal plane


def test_lightfield_row_spans_the_view_cone():
    vs = lightfield_row(48, 40.0, 1.0, Fov.symmetric(30, 0.75), (30, 40))
    xs = [v.pose.position[0] for v in vs]
    assert xs[0] < xs[-1]
    assert xs[-1] - xs[0] == pytest.approx(2 * math.tan(math.radians(20)))


SHADER = """
#include "views.glsl"
layout(local_size_x = 1) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) buffer Out { vec4 outv[]; };
uniform vec3 point;
uniform vec2 pixel;
void main() {
    uint v = gl_GlobalInvocationID.x;
    outv[v * 3u] = views[v].view_proj * vec4(point, 1.0);
    vec3 o, d;
    view_primary_ray(v, pixel, o, d);
    outv[v * 3u + 1u] = vec4(o, float(view_count()));
    outv[v * 3u + 2u] = vec4(d, float(frame_index()));
}
"""


def test_glsl_reads_the_packed_views_like_numpy(gl, tmp_path):
    from rayvr.gpu import compute_program
    from rayvr.gpu.bindings import BINDINGS

    src = tmp_path / "probe.comp"
    src.write_text(SHADER)
    prog = compute_program(gl, src)
    p = PRESETS["index"]
    vs = stereo_views(HEAD, p.ipd, p.left_fov, p.right_fov, (96, 80))
    origin = vs.origin()
    views_buf = gl.buffer(vs.pack(origin, frame_index=5))
    out = gl.buffer(reserve=2 * 3 * 16)
    views_buf.bind_to_storage_buffer(BINDINGS["RAYVR_VIEWS_SSBO"])
    out.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    world_point = _ahead(HEAD, 3.0) + [0.2, 0.1, 0.0]
    prog["point"] = tuple(world_point - origin)
    prog["pixel"] = (20.5, 60.5)
    prog.run(2, 1, 1)
    res = np.frombuffer(out.read(), dtype=np.float32).reshape(2, 3, 4)
    for i, v in enumerate(vs):
        clip = res[i, 0]
        assert np.allclose(((clip[:2] / clip[3]) + 1) / 2 * [96, 80], v.project(world_point)[:2], atol=1e-2)
        o, d = v.primary_ray((20.5, 60.5), origin)
        assert np.allclose(res[i, 1, :3], o, atol=1e-5) and res[i, 1, 3] == 2
        assert np.allclose(res[i, 2, :3], d, atol=1e-5) and res[i, 2, 3] == 5


def test_camera_grid_baseline_is_first_to_last():
    vs = camera_grid(5, 1, None, Fov.symmetric(40, 1), (8, 8), baseline=0.4)
    assert vs[4].pose.position[0] - vs[0].pose.position[0] == pytest.approx(0.4)
    with pytest.raises(OptionError, match="spacing"):
        camera_grid(2, 2, None, Fov.symmetric(40, 1), (8, 8))


def test_a_scene_millimetres_across_without_a_camera_is_framed_in_front_of_the_near_plane(gpu):
    """The framing camera of a scene with no camera keeps its near plane in front of the scene,
    however small (a 5 mm quad, the size of some glTF samples): it renders as the same quad a
    metre across does, red in the centre, the environment in the corners."""
    import rayvr as rv
    from rayvr.scene import builtin
    from rayvr.xr.cameras import default_views

    images = []
    for size in (0.005, 1.0):
        scene = builtin.quad(size, builtin.lambert("Quad", (0.8, 0.2, 0.2)))
        scene.cameras.clear()
        views = default_views(scene, 1, (16, 16))
        assert views.views[0].near < 0.1 * float(np.linalg.norm(views.views[0].pose.position))
        with rv.Renderer(scene, rv.graphs.hybrid(), views=views) as r:
            r.render()
            images.append(r.read_output("ToneMap.dst")[0, ..., :3].astype(np.int32))
    small, large = images
    assert small[8, 8, 0] > small[8, 8, 1] + 40 and small[0, 0, 0] == small[0, 0, 1]
    assert np.abs(small - large).max() <= 2
