"""The GPU scene's per-frame part (rayvr.scene.gpu_frame): a moving head shifts render space
without rebuilding the TLAS or re-uploading instances and lights, renders the same pixels as a
scene built at that origin, and re-anchors once the shift grows past its bound."""
import numpy as np

import rayvr as rv
from rayvr.scene import GpuScene, builtin
from rayvr.scene.gpu_frame import RECENTRE_FRACTION
from rayvr.xr.cameras import default_views
from rayvr.xr.views import Pose, View, ViewSet


def moved(view_set, offset):
    return ViewSet([View(Pose(v.pose.position + offset, v.pose.orientation), v.fov, v.width, v.height, v.near, v.far)
                    for v in view_set])


def test_a_walking_head_shifts_render_space_without_rebuilding(gpu):
    scene = builtin.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    base = default_views(scene, 2, (32, 32))
    step = np.array([0.02, 0.0, -0.03])
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=base, gpu=gpu) as walking:
        for k in range(1, 6):
            walking.render(moved(base, k * step))
        rebuilds = walking.gpu_scene.frame.rebuilds
        version = walking.gpu_scene.version
        walking.render(moved(base, 6 * step))
        assert walking.gpu_scene.frame.rebuilds == rebuilds and walking.gpu_scene.version == version
        assert np.linalg.norm(walking.gpu_scene.frame.shift) > 0
        walked = walking.read_output(rv.graphs.HDR_OUTPUT)
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=moved(base, 6 * step), gpu=gpu) as fresh:
        fresh.frame_index = walking.frame_index - 1   # the same random numbers as the last walked frame
        fresh.render()
        assert np.linalg.norm(fresh.gpu_scene.frame.shift) == 0
        direct = fresh.read_output(rv.graphs.HDR_OUTPUT)
    # the same radiance up to the float32 rounding of the shift (a handful of edge pixels may differ)
    close = np.isclose(walked, direct, rtol=1e-3, atol=1e-4).all(axis=-1)
    assert close.mean() > 0.995, close.mean()


def test_moving_instances_or_lights_rebuilds_and_a_long_walk_reanchors(gpu):
    scene = builtin.cornell_box()
    gs = GpuScene(gpu, scene)
    try:
        gs.update(np.zeros(3))
        rebuilds, version = gs.frame.rebuilds, gs.version
        gs.update(np.array([0.05, 0, 0]))                       # a step: the shift alone
        assert (gs.frame.rebuilds, gs.version) == (rebuilds, version)
        scene.instances[1].transform[:3, 3] += (0.0, 0.01, 0.0)  # an edit: the TLAS follows
        gs.update(np.array([0.05, 0, 0]))
        assert gs.frame.rebuilds == rebuilds + 1 and gs.version == version + 1
        far = np.array([2.0 * RECENTRE_FRACTION * gs.scale, 0.0, 0.0])
        gs.update(far)                                          # past the bound: re-anchored here
        np.testing.assert_array_equal(gs.frame.anchor, far)
        assert gs.frame.rebuilds == rebuilds + 2
    finally:
        gs.release()


def test_scene_instances_are_one_array(gpu):
    scene = builtin.instanced_boxes()
    t = scene.instances.transforms
    assert t.shape == (len(scene.instances), 4, 4) and t.dtype == np.float64
    scene.instances[2].transform[:3, 3] = (7.0, 8.0, 9.0)      # a view of the row
    np.testing.assert_array_equal(scene.instances.transforms[2, :3, 3], (7.0, 8.0, 9.0))
    scene.instances[3].transform = np.diag([2.0, 2.0, 2.0, 1.0])
    assert scene.instances.transforms[3, 0, 0] == 2.0
