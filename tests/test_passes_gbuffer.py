"""GBufferRaster: what each target holds (positions, normals, material values, effect ids, linear
depth, motion vectors), alpha masking, and camera-relative precision far from the origin."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.materials.material import Material
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Camera, Scene
from rayvr.xr.cameras import default_views

PINS = ("posW", "normW", "faceNormalW", "baseColor", "metalRough", "emissive", "effect", "motion")


def gbuffer_graph():
    g = rv.RenderGraph("GBufferOnly")
    g.add_pass(rv.passes.GBufferRaster(), "GBuffer")
    for pin in PINS:
        g.mark_output(f"GBuffer.{pin}")
    return g


def two_materials() -> Scene:
    """Left half: a rough red dielectric (SHADOWS); right half: an emissive metal (REFLECTIONS)."""
    s = Scene("halves")
    s.add_material(Material("Red", base_color=(0.8, 0.1, 0.1, 1.0), metallic=0.0, roughness=0.7))
    s.add_material(Material("Metal", base_color=(0.2, 0.4, 0.6, 1.0), metallic=1.0, roughness=0.25,
                            emissive=(0.5, 0.25, 0.125), effect=rv.Effect.REFLECTIONS))
    s.add_object("Left", *builtin.quad_mesh([(-1, -1, 0), (0, -1, 0), (0, 1, 0), (-1, 1, 0)], (0, 0, 1)), "Red")
    s.add_object("Right", *builtin.quad_mesh([(0, -1, 0), (1, -1, 0), (1, 1, 0), (0, 1, 0)], (0, 0, 1)), "Metal")
    s.cameras.append(Camera.look_at((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), yfov_deg=60.0))
    return s


def test_targets_hold_the_surface_values(gpu):
    scene = two_materials()
    with Renderer(scene, gbuffer_graph(), views=2, size=(32, 32)) as r:
        r.render()
        out = {pin: r.read_output(f"GBuffer.{pin}") for pin in PINS}
        origin = r.view_set.origin()
        eyes = [v.pose.position for v in r.view_set.views]
    pos = out["posW"][..., :3] + origin
    assert np.allclose(pos[..., 2], 0.0, atol=1e-5)
    for v, eye in enumerate(eyes):   # linear depth is the eye-space distance along -z
        np.testing.assert_allclose(out["posW"][v, ..., 3], eye[2] - pos[v, ..., 2], rtol=1e-5)
    for pin in ("normW", "faceNormalW"):
        n = out[pin][..., :3].astype(np.float64)
        np.testing.assert_allclose(n, np.broadcast_to([0.0, 0.0, 1.0], n.shape), atol=1e-3)
    left, right = pos[..., 0] < -0.02, pos[..., 0] > 0.02
    effect, material = out["effect"][..., 0] & 0xFF, out["effect"][..., 0] >> 8
    assert (effect[left] == rv.Effect.SHADOWS).all() and (material[left] == 0).all()
    assert (effect[right] == rv.Effect.REFLECTIONS).all() and (material[right] == 1).all()
    np.testing.assert_allclose(out["baseColor"][left][:, :3].astype(np.float64), [[0.8, 0.1, 0.1]] * int(left.sum()),
                               rtol=1e-3)
    np.testing.assert_allclose(out["metalRough"][right].astype(np.float64), [[1.0, 0.25]] * int(right.sum()), atol=1e-3)
    np.testing.assert_allclose(out["emissive"][right][:, :3].astype(np.float64), [[0.5, 0.25, 0.125]] * int(right.sum()),
                               atol=1e-3)
    assert (out["emissive"][left][:, :3] == 0).all()
    assert np.abs(out["motion"]).max() == 0          # first frame: no motion


def test_sky_pixels_are_marked_no_geometry(gpu):
    scene = builtin.quad(size=0.5)
    with Renderer(scene, gbuffer_graph(), views=1, size=(32, 32)) as r:
        r.render()
        pos, effect = r.read_output("GBuffer.posW"), r.read_output("GBuffer.effect")[..., 0]
    sky = pos[..., 3] == 0
    assert 0 < sky.sum() < sky.size
    assert (effect[sky] == 0xFF).all() and (effect[~sky] != 0xFF).all()


def test_motion_vectors_follow_the_camera(gpu):
    scene = two_materials()
    views = default_views(scene, 1, (32, 32))
    with Renderer(scene, gbuffer_graph(), views=views) as r:
        r.render()
        r.view_set.views[0].pose.position = r.view_set.views[0].pose.position + np.array([0.05, 0.0, 0.0])
        r.render()
        motion = r.read_output("GBuffer.motion")
    # a fronto-parallel plane at distance 1 shifts by -dx * f pixels when the camera moves +dx
    f = 32 / (2 * np.tan(np.radians(30.0)))
    np.testing.assert_allclose(motion[0, 4:-4, 4:-4, 0], -0.05 * f, atol=0.05)
    np.testing.assert_allclose(motion[0, 4:-4, 4:-4, 1], 0.0, atol=0.05)


def test_alpha_masked_material_is_cut_out(gpu):
    scene = builtin.quad(material=Material("Cut", base_color=(1, 1, 1, 0.3), metallic=0.0,
                                           alpha_mode="MASK", alpha_cutoff=0.5))
    with Renderer(scene, gbuffer_graph(), views=1, size=(16, 16)) as r:
        assert r.compiled.passes["GBuffer"].defines()["SCENE_HAS_ALPHA_MASK"] == 1
        r.render()
        assert (r.read_output("GBuffer.posW")[..., 3] == 0).all()
        scene.materials["Cut"].alpha_cutoff = 0.2        # now it passes
        r.render()
        assert (r.read_output("GBuffer.posW")[..., 3] > 0).any()


def test_far_from_the_origin_renders_like_near_it(gpu):
    """Camera-relative rendering: the same scene 1e6 m away gives the same image."""
    shift = np.array([1.0e6, 0.0, -1.0e6])
    images = []
    for offset in (np.zeros(3), shift):
        scene = builtin.box_on_plane(light_height=1.0)
        for inst in scene.instances:
            inst.transform[:3, 3] += offset
        scene.lights[0].position = scene.lights[0].position + offset
        scene.cameras[:] = [Camera.look_at(np.array([1.5, 2.0, 1.5]) + offset, offset)]
        with Renderer(scene, rv.graphs.hybrid(preset="raw"), views=2, size=(32, 32)) as r:
            r.render()
            images.append(r.read_output("Composite.color").astype(np.float64))
    near, far = images
    assert near.max() > 0
    close = np.abs(far - near) <= 0.01 * np.abs(near) + 1e-3
    assert close.mean() > 0.99      # a few shadow-edge pixels may flip


def test_multiview_and_layered_draw_the_same_gbuffer(gpu):
    """Runs where the driver has GL_OVR_multiview2 (NVIDIA); llvmpipe has only the layered path."""
    if not gpu.caps.multiview:
        pytest.skip("no GL_OVR_multiview2 on this driver (layered rendering is tested everywhere)")
    scene = two_materials()
    out = {}
    for mode in ("on", "off"):
        g = rv.RenderGraph("GBufferOnly")
        g.add_pass(rv.passes.GBufferRaster(multiview=mode), "GBuffer")
        for pin in PINS:
            g.mark_output(f"GBuffer.{pin}")
        with Renderer(scene, g, views=2, size=(32, 32)) as r:
            r.render()
            assert r.compiled.passes["GBuffer"]._multiview == (mode == "on")
            out[mode] = {pin: r.read_output(f"GBuffer.{pin}") for pin in PINS}
    for pin in PINS:
        np.testing.assert_array_equal(out["on"][pin], out["off"][pin], err_msg=pin)


def test_multiview_on_without_the_extension_is_refused(gpu):
    if gpu.caps.multiview:
        pytest.skip("the driver has multiview")
    g = rv.RenderGraph("GBufferOnly")
    g.add_pass(rv.passes.GBufferRaster(multiview="on"), "GBuffer")
    g.mark_output("GBuffer.posW")
    with pytest.raises(rv.GpuError, match="multiview='auto'"):
        Renderer(builtin.quad(), g, views=2, size=(8, 8))


def test_taa_jitter_moves_the_raster_sample_like_the_rays(gpu):
    """With jitter j the G-buffer samples pixel centre + j, as view_primary_ray does."""
    from rayvr.passes.taa import halton_jitter

    scene = two_materials()
    views = default_views(scene, 1, (16, 16))
    j = np.array(halton_jitter(1))         # frame 1's: both components away from 0
    assert np.abs(j).min() > 0.05
    with Renderer(scene, gbuffer_graph(), views=views, jitter=True) as r:
        r.render()
        r.render()
        pos = r.read_output("GBuffer.posW")[0, ..., :3].astype(np.float64)
        origin = views.origin()
    v = views[0]
    for x, y in [(3, 4), (8, 8), (12, 10)]:
        o, d = v.primary_ray((x + 0.5 + j[0], y + 0.5 + j[1]), origin)
        want = o + d * (-(o[2] + origin[2]) / d[2])          # the plane z = 0 in world space
        np.testing.assert_allclose(pos[y, x], want, atol=2e-4)
