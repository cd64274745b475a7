"""Stereo registration (the Ray-VR paper's problem): each view's rays and raster come from that
view's own matrices, so a point at distance d shows a disparity of IPD * f / d in both the raster
G-buffer and ray-traced hits; a point at infinity lands on the same pixel in both eyes; mono and
view 0 of stereo agree pixel for pixel."""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.gpu.shaders import compute_program
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Scene
from rayvr.xr.cameras import stereo_views
from rayvr.xr.views import Fov, Pose, View, ViewSet

SIZE = (48, 40)
IPD = 0.064
FOV = Fov.symmetric(60.0, SIZE[0] / SIZE[1])
F_PX = SIZE[0] / (math.tan(FOV.angle_right) - math.tan(FOV.angle_left))   # focal length in pixels


def wall(distance: float) -> Scene:
    """A large Lambert wall at z = -distance facing the cameras at the origin, lit by a point light."""
    s = Scene("wall")
    s.add_material(builtin.lambert("Wall", (0.8, 0.8, 0.8)))
    h = distance * 2.0
    s.add_object("Wall", *builtin.quad_mesh([(-h, -h, -distance), (h, -h, -distance), (h, h, -distance),
                                             (-h, h, -distance)], (0, 0, 1)), "Wall")
    s.lights.append(rv.scene.Light("point", position=(0.0, 0.0, 0.0), intensity=distance ** 2))
    return s


def stereo(far=1000.0):
    return stereo_views(Pose(), IPD, FOV, FOV, SIZE, near=0.05, far=far)


def crossing(xs_world: np.ndarray, target: float = 0.0) -> float:
    """Sub-pixel x (pixel units, pixel centres at i + 0.5) where the row's world x crosses `target`."""
    i = int(np.searchsorted(xs_world, target)) - 1
    a, b = xs_world[i], xs_world[i + 1]
    return i + 0.5 + (target - a) / (b - a)


RAY_SHADER = """
#include "views.glsl"
#include "scene.glsl"
#include "ray_query.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Hits { vec4 hits[]; };
void main() {
    uvec3 p = gl_GlobalInvocationID;
    vec2 size = views[p.z].clip.zw;
    if (p.x >= uint(size.x) || p.y >= uint(size.y)) return;
    vec3 o, d;
    view_primary_ray(p.z, vec2(p.xy) + 0.5, o, d);
    Hit h;
    vec4 r = vec4(0.0);
    if (trace_closest(o, d, 1e30, h)) r = vec4(o + d * h.t, 1.0);
    hits[(p.z * uint(size.y) + p.y) * uint(size.x) + p.x] = r;
}
"""


def ray_traced_positions(renderer, tmp_path) -> np.ndarray:
    """Primary-ray hit positions (views, h, w, 4) from each view's own ray generation."""
    path = tmp_path / "primary.comp"
    path.write_text(RAY_SHADER)
    gl = renderer.gl
    prog = compute_program(gl, path, renderer.gpu_scene.defines())
    w, h = renderer.size
    out = gl.buffer(reserve=16 * w * h * renderer.view_count)
    out.bind_to_storage_buffer(16)
    renderer.views_buffer.bind_to_storage_buffer(0)
    renderer.gpu_scene.bind()
    prog.run((w + 7) // 8, (h + 7) // 8, renderer.view_count)
    gl.finish()
    return np.frombuffer(out.read(), np.float32).reshape(renderer.view_count, h, w, 4)


@pytest.mark.parametrize("distance", [1.5, 6.0])
def test_disparity_is_ipd_f_over_d_in_raster_and_rays(gpu, tmp_path, distance):
    g = rv.graphs.hybrid(preset="raw")
    g.mark_output("GBuffer.posW")
    with Renderer(wall(distance), g, views=stereo()) as r:
        r.render()
        raster = r.read_output("GBuffer.posW")
        rays = ray_traced_positions(r, tmp_path)
        origin = r.view_set.origin()
    want = IPD * F_PX / distance
    row = SIZE[1] // 2
    for name, pos in (("raster", raster), ("rays", rays)):
        assert (pos[..., 3] > 0).all(), name
        xs = pos[:, row, :, 0].astype(np.float64) + origin[0]
        x_left, x_right = crossing(xs[0]), crossing(xs[1])
        assert x_left - x_right == pytest.approx(want, abs=0.5), name
    # raster and rays see the same surface point through every pixel of every view
    np.testing.assert_allclose(rays[..., :3], raster[..., :3], atol=2e-4 * distance)


def test_point_at_infinity_lands_on_the_same_pixel(gpu, tmp_path):
    distance = 1e5
    g = rv.graphs.hybrid(preset="raw")
    g.mark_output("GBuffer.posW")
    with Renderer(wall(distance), g, views=stereo(far=1e6)) as r:
        r.render()
        raster = r.read_output("GBuffer.posW")
        rays = ray_traced_positions(r, tmp_path)
        origin = r.view_set.origin()
    row = SIZE[1] // 2
    for pos in (raster, rays):
        xs = pos[:, row, :, 0].astype(np.float64) + origin[0]
        assert abs(crossing(xs[0]) - crossing(xs[1])) < 0.05


def test_mono_and_view_zero_of_stereo_agree(gpu):
    scene = builtin.cornell_box()
    scene.materials["Floor"].effect = rv.Effect.REFLECTIONS
    from rayvr.xr.cameras import camera_pose

    head, yfov = camera_pose(scene)
    views = stereo_views(head, IPD, FOV, FOV, SIZE)
    mono = ViewSet([View(views[0].pose, views[0].fov, *SIZE)])
    out = []
    for vs in (mono, views):
        with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=vs) as r:
            r.render()
            out.append(r.read_output())
    assert out[0].shape[0] == 1 and out[1].shape[0] == 2
    np.testing.assert_array_equal(out[0][0], out[1][0])
