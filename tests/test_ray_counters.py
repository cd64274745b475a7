"""Rays per view (rayvr.rendergraph.ray_counters): the ray passes count the queries they begin on
GPU counters per view, the profile carries them a frame late, and the counts are exact: a plane
under one point light traces one shadow ray per light sample and SHADOWS pixel of each view."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.xr.cameras import camera_grid, stereo_views
from rayvr.xr.views import Fov, Pose

SIZE = (24, 20)


def plane_views(n: int = 2):
    """Eyes above the lit plane, looking straight down at it, so every pixel sees the plane: a
    stereo pair, or a row of n cameras (the ray passes' workgroups then mix views)."""
    down = Pose([0.0, 3.0, 0.0], [-np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])
    fov = Fov.symmetric(40.0, SIZE[0] / SIZE[1])
    if n == 2:
        return stereo_views(down, 0.2, fov, fov, SIZE)
    return camera_grid(n, 1, 0.05, fov, SIZE, center_pose=down)


@pytest.mark.parametrize("light_samples, views", [(1, 2), (3, 2), (1, 5)])
def test_shadow_rays_per_view_are_one_per_light_sample_and_pixel(gpu, light_samples, views):
    scene = builtin.plane_with_point_light()
    scene.materials["Plane"].effect = rv.Effect.SHADOWS
    g = rv.graphs.hybrid(preset="raw", light_samples=light_samples)
    g.mark_output("GBuffer.effect")
    with Renderer(scene, g, views=plane_views(views)) as r:
        r.render()
        counts = r.compiled.ray_counts()
        effect = r.read_output("GBuffer.effect")[..., 0] & 0xFF
    lit = (effect == int(rv.Effect.SHADOWS)).reshape(views, -1).sum(axis=1)
    assert lit.min() > 0.9 * SIZE[0] * SIZE[1]
    assert counts == [light_samples * int(n) for n in lit]


def test_the_profile_carries_the_last_frames_counts_and_no_ray_pass_counts_none(gpu):
    scene = builtin.plane_with_point_light()
    scene.materials["Plane"].effect = rv.Effect.SHADOWS
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=plane_views()) as r:
        for _ in range(3):
            r.render()
        exact = r.compiled.ray_counts()
        p = r.profile()
        assert p.rays_per_view == exact and p.rays_total == sum(exact) > 0
        assert "rays traced (last frame)" in str(p)
        assert p.as_dict()["rays_per_view"] == exact
    scene.materials["Plane"].effect = rv.Effect.RASTER   # no ray pass is left: no counters
    with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=plane_views()) as r:
        r.render()
        assert r.compiled.rays is None and r.profile().rays_per_view == [] and r.profile().rays_total == 0


def test_path_tracer_kernels_count_the_same_rays(gpu):
    """The megakernel and the wavefront trace the same paths: the same count per view."""
    scene = builtin.cornell_box()
    scene.materials["TallBox"].effect = rv.Effect.PATH_TRACED
    counts = []
    for kernel in ("megakernel", "wavefront"):
        g = rv.graphs.hybrid(preset="raw")
        g.update_pass("PathTracer", {"kernel": kernel})
        with Renderer(scene, g, views=2, size=(16, 16)) as r:
            r.render()
            counts.append(r.compiled.ray_counts())
    assert counts[0] == counts[1] and min(counts[0]) > 0
