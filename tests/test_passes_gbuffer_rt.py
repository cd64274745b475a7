"""GBufferRT against GBufferRaster pin by pin (stereo, motion, alpha mask, far from the origin,
TAA jitter), and GBufferAuto's choice between them."""
import types

import numpy as np
import pytest

import rayvr as rv
from rayvr.gpu.context import is_weak_raster
from rayvr.materials.material import Material
from rayvr.passes.dispatch import ray_group
from rayvr.passes.gbuffer.auto import choose_gbuffer
from rayvr.passes.gbuffer import GBufferRT
from rayvr.renderer import Renderer
from rayvr.xr.cameras import default_views
from rayvr.scene import builtin
from rayvr.scene.model import Camera

PINS = ("posW", "normW", "faceNormalW", "baseColor", "metalRough", "emissive", "effect", "motion")


def gbuffer_graph(kind: str, rt_props: dict | None = None):
    g = rv.RenderGraph("GBufferOnly")
    g.add_pass(rv.passes.GBufferRT(rt_props) if kind == "rt" else rv.passes.GBufferRaster(), "GBuffer")
    for pin in PINS:
        g.mark_output(f"GBuffer.{pin}")
    return g


def render_both(scene, views, size, move=None, setup=None, rt_props=None, **renderer_kw):
    """Both G-buffers of the same frame(s) of `views` default views: {kind: {pin: array}}.
    `setup(view_set)` runs before the first frame, `move(view_set)` between two frames (motion);
    `rt_props`: GBufferRT's properties."""
    out = {}
    for kind in ("raster", "rt"):
        view_set = default_views(scene, views, size)
        if setup is not None:
            setup(view_set)
        with Renderer(scene, gbuffer_graph(kind, rt_props), views=view_set, **renderer_kw) as r:
            r.render()
            if move is not None:
                move(r.view_set)
                r.render()
            out[kind] = {pin: r.read_output(f"GBuffer.{pin}") for pin in PINS}
    return out


def interior(effect: np.ndarray) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood has one effect word (silhouettes and material edges excluded)."""
    e = effect[..., 0].astype(np.int64)
    pad = np.pad(e, ((0, 0), (1, 1), (1, 1)), mode="edge")
    same = np.ones(e.shape, bool)
    h, w = e.shape[1:]
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            same &= pad[:, dy:dy + h, dx:dx + w] == e
    return same


def assert_same_gbuffer(out, min_interior=0.3):
    ra, rt = out["raster"], out["rt"]
    mask = interior(ra["effect"]) & interior(rt["effect"])
    assert mask.mean() > min_interior, f"only {mask.mean():.2f} of the pixels are interior"
    np.testing.assert_array_equal(ra["effect"][mask], rt["effect"][mask], err_msg="effect")
    hit = mask & (ra["effect"][..., 0] != 0xFF)
    assert hit.any()
    pos_a, pos_b = ra["posW"][hit].astype(np.float64), rt["posW"][hit].astype(np.float64)
    scale = np.abs(pos_a).max()
    np.testing.assert_allclose(pos_b[:, :3], pos_a[:, :3], atol=1e-4 * scale, err_msg="posW")
    np.testing.assert_allclose(pos_b[:, 3], pos_a[:, 3], rtol=1e-4, err_msg="posW.w (linear depth)")
    for pin in ("normW", "faceNormalW"):
        np.testing.assert_allclose(rt[pin][hit][:, :3].astype(np.float64), ra[pin][hit][:, :3].astype(np.float64),
                                   atol=2e-3, err_msg=pin)
    for pin in ("baseColor", "metalRough", "emissive"):
        np.testing.assert_array_equal(rt[pin][mask], ra[pin][mask], err_msg=pin)
    np.testing.assert_allclose(rt["motion"][hit].astype(np.float64), ra["motion"][hit].astype(np.float64),
                               atol=2e-2, err_msg="motion")
    sky = mask & (ra["effect"][..., 0] == 0xFF)
    for pin in PINS:   # sky pixels hold the raster path's clear values exactly
        np.testing.assert_array_equal(rt[pin][sky], ra[pin][sky], err_msg=f"{pin} on sky pixels")


def test_rt_equals_raster_in_stereo_with_motion(gpu):
    scene = builtin.spheres(n=2, subdivisions=2)
    views, size = 2, (48, 48)

    def move(view_set):
        for v in view_set.views:
            v.pose.position = v.pose.position + np.array([0.04, -0.02, 0.03])

    out = render_both(scene, views, size, move)
    assert np.abs(out["raster"]["motion"]).max() > 0.3         # the camera moved: motion to compare
    assert (out["raster"]["effect"][..., 0] == 0xFF).any()       # some sky to compare too
    assert_same_gbuffer(out)
    for kind in out:   # both views got their own image
        assert not np.array_equal(out[kind]["posW"][0], out[kind]["posW"][1])


def test_rt_equals_raster_in_a_camera_grid_whose_views_straddle_workgroups(gpu, monkeypatch):
    # 6 views in workgroups spanning 4 (passes.dispatch.ray_group; GBufferRT's own default is 2):
    # the second workgroup along z has two views past the last one, and 40x36 pixels are no
    # multiple either.
    props = {"view_group": 4}
    assert ray_group(6, view_group=GBufferRT(props).view_group)[2] == 4
    scene = builtin.spheres(n=2, subdivisions=2)
    out = render_both(scene, 6, (40, 36), rt_props=props)
    assert_same_gbuffer(out)
    pos = out["rt"]["posW"]
    assert all(not np.array_equal(pos[i], pos[i + 1]) for i in range(5)), "a view repeated its neighbour"


def test_ray_group_spans_views_only_in_camera_grids():
    assert ray_group(2) == (8, 8, 1)                  # stereo: the eyes see a pixel's surface far apart
    assert ray_group(2, view_group=2) == (8, 8, 1)
    assert ray_group(64) == (4, 4, 4)                 # 64 threads: 4x4 pixels in each of 4 views
    assert ray_group(64, view_group=2) == (8, 4, 2)
    assert ray_group(64, (8, 4)) == (4, 2, 4)
    assert ray_group(64, view_group=1) == (8, 8, 1)
    assert ray_group(6, (8, 4), 16) == (4, 2, 4)      # fewer views than asked for: the largest power of two
    assert ray_group(3, (8, 4), 16) == (8, 4, 1)


def test_alpha_masked_quad_is_seen_through_like_the_raster(gpu):
    """A veil of alpha 0.3 between the camera and a box: cut out at cutoff 0.5, drawn at 0.2."""
    scene = builtin.box_on_plane()
    scene.add_material(Material("Cut", base_color=(1, 1, 1, 0.3), metallic=0.0, alpha_mode="MASK",
                                alpha_cutoff=0.5))
    scene.add_object("Veil", *builtin.quad_mesh([(-2, 0.3, 1), (2, 0.3, 1), (2, 3, 1), (-2, 3, 1)], (0, 0, 1)), "Cut")
    scene.cameras[:] = [Camera.look_at((0.0, 1.5, 2.5), (0.0, 0.2, 0.0))]
    cut = scene.materials.index("Cut")
    for cutoff, veil in ((0.5, False), (0.2, True)):
        scene.materials["Cut"].alpha_cutoff = cutoff
        out = render_both(scene, 1, (32, 32))
        for kind in out:
            drawn = (out[kind]["effect"][..., 0] >> 8 == cut).mean()
            assert (drawn > 0.5) if veil else (drawn == 0), f"{kind}: veil covers {drawn:.2f} at cutoff {cutoff}"
        assert_same_gbuffer(out)


def test_rt_equals_raster_far_from_the_origin(gpu):
    shift = np.array([1.0e6, 0.0, -1.0e6])
    scene = builtin.box_on_plane()
    for inst in scene.instances:
        inst.transform[:3, 3] += shift
    scene.cameras[:] = [Camera.look_at(np.array([1.5, 2.0, 1.5]) + shift, shift)]
    views, size = 2, (32, 32)
    out = render_both(scene, views, size)
    assert_same_gbuffer(out)
    depth = out["rt"]["posW"][..., 3]
    assert depth.max() < 10.0 and (depth > 0).mean() > 0.5      # render space stays near the head


def test_rt_follows_the_taa_jitter_like_the_raster(gpu):
    scene = builtin.box_on_plane()
    views, size = 2, (32, 32)
    out = render_both(scene, views, size, move=lambda view_set: None, jitter=True)   # frame 1: jittered
    assert_same_gbuffer(out)
    plain = render_both(scene, views, size)
    assert not np.array_equal(out["rt"]["posW"], plain["rt"]["posW"]), "jitter did not move the rays"


def test_rt_clips_at_the_near_and_far_planes_like_the_raster(gpu):
    """box_on_plane from above: the near plane cuts the box's top, the far plane the plane's edge."""
    scene = builtin.box_on_plane()
    scene.cameras[:] = [Camera.look_at((0.0, 1.2, 1.2), (0.0, 0.0, 0.0))]

    def clip_planes(view_set):
        for v in view_set.views:
            v.near, v.far = 1.1, 2.0

    out = render_both(scene, 1, (32, 32), setup=clip_planes)
    for kind in out:
        depth = out[kind]["posW"][..., 3]
        seen = depth > 0
        assert 0.2 < seen.mean() < 0.9, f"{kind}: the clip planes cut nothing ({seen.mean():.2f} seen)"
        assert depth[seen].min() >= 1.1 - 1e-4 and depth[seen].max() <= 2.0 + 1e-4, kind
    assert_same_gbuffer(out, min_interior=0.2)


def test_auto_chooses_raster_here_and_rt_on_weak_raster_gpus(gpu):
    here = "rt" if gpu.caps.weak_raster else "raster"    # llvmpipe rasterises; an H100 traces
    assert gpu.caps.weak_raster == is_weak_raster(gpu.caps.renderer)
    assert choose_gbuffer("auto", gpu.caps)[0] == here
    h100 = types.SimpleNamespace(weak_raster=True, renderer="NVIDIA H100 80GB HBM3/PCIe/SSE2")
    kind, why = choose_gbuffer("auto", h100)
    assert kind == "rt" and "H100" in why
    assert choose_gbuffer("auto", h100, cull_back_faces=True)[0] == "raster"
    assert choose_gbuffer("raster", h100)[0] == "raster"

    for name in ("NVIDIA H100 PCIe/PCIe/SSE2", "NVIDIA H200/PCIe/SSE2", "NVIDIA GH200 480GB/PCIe/SSE2",
                 "NVIDIA A100-SXM4-80GB/PCIe/SSE2", "NVIDIA B200/PCIe/SSE2", "NVIDIA H800/PCIe/SSE2"):
        assert is_weak_raster(name), name
    for name in ("NVIDIA GeForce RTX 4090/PCIe/SSE2", "NVIDIA RTX A6000/PCIe/SSE2", "NVIDIA L40S/PCIe/SSE2",
                 "llvmpipe (LLVM 15.0.7, 256 bits)", "AMD Radeon RX 7900 XTX"):
        assert not is_weak_raster(name), name


def test_hybrid_gbuffer_option_renders_the_same_image(gpu):
    scene = builtin.box_on_plane()
    images = {}
    for mode in ("raster", "rt"):   # forced both ways, so every driver compares the two
        with Renderer(scene, rv.graphs.hybrid(preset="raw", gbuffer=mode), views=2, size=(32, 32)) as r:
            r.render()
            assert r.compiled.passes["GBuffer"].chosen == mode
            assert ("GBufferRT" if mode == "rt" else "GBufferRaster") in str(r.report())
            images[mode] = r.read_output("Composite.color").astype(np.float64)
    close = np.abs(images["rt"] - images["raster"]) <= 0.01 * np.abs(images["raster"]) + 1e-3
    assert images["raster"].max() > 0 and close.mean() > 0.97     # silhouette pixels may differ


def test_unknown_gbuffer_mode_is_refused(gpu):
    with pytest.raises(rv.OptionError, match="'mode' is 'fast'; use 'auto', 'raster' or 'rt'"):
        rv.graphs.hybrid(preset="raw", gbuffer="fast")


@pytest.mark.parametrize("suffix", [".json", ".py"])
def test_hybrid_with_rt_gbuffer_saves_and_loads(tmp_path, suffix):
    g = rv.graphs.hybrid(preset="raw", gbuffer="rt")
    loaded = rv.RenderGraph.load(g.save(tmp_path / f"hybrid{suffix}"))
    gb = loaded.passes["GBuffer"]
    assert type(gb).__name__ == "GBufferAuto" and gb.mode == "rt"


def test_the_raster_reads_each_pixel_of_a_quad_at_its_own_mip_level(gpu):
    """Four flat quadrants far apart in colour, seen about a texel a pixel: away from the seams
    every pixel is one quadrant's colour, and the raster's texel is the ray-traced G-buffer's. The
    raster's mip selection once used implicit derivatives inside the material's texture branches,
    where they are undefined: llvmpipe blended the quadrants at one pixel of many 2x2 quads (a dot
    lattice over Khronos' ToyCar)."""
    from rayvr.materials.material import TextureRef
    from rayvr.scene.model import Texture

    n = 64
    img = np.zeros((n, n, 4), np.uint8)
    img[..., 3] = 255
    img[:n // 2, :n // 2, 0] = img[:n // 2, n // 2:, 1] = img[n // 2:, :n // 2, 2] = 255
    img[n // 2:, n // 2:, :3] = 255
    scene = builtin.quad(material=Material("Quadrants", metallic=0.0, base_color_texture=TextureRef(0)))
    scene.textures.append(Texture(img))
    out = render_both(scene, 1, (48, 48))
    mask = interior(out["raster"]["effect"])[0] & interior(out["rt"]["effect"])[0]
    mask &= out["raster"]["effect"][0, ..., 0] != 0xFF
    raster, rt = (out[k]["baseColor"][0][..., :3].astype(np.float64) for k in ("raster", "rt"))
    pure = np.minimum(rt, 1.0 - rt).max(axis=-1) < 0.05   # one quadrant's colour: away from the seams
    assert mask.sum() > 400 and (pure & mask).sum() > 0.7 * mask.sum()
    assert np.abs(raster - rt).max(axis=-1)[mask & pure].max() < 0.02


def test_rt_reads_textures_at_the_level_the_raster_chooses(gpu):
    # A checkerboard of single texels seen from afar: each pixel covers many texels, so the
    # raster's derivatives pick a coarse mip level (flat grey), and so must GBufferRT's ray cones;
    # reading level 0 would alias into black and white pixels.
    from rayvr.materials.material import TextureRef
    from rayvr.scene.model import Texture

    n = 256
    checks = (np.indices((n, n)).sum(axis=0) % 2 * 255).astype(np.uint8)
    img = np.stack([checks, checks, checks, np.full((n, n), 255, np.uint8)], axis=-1)
    scene = builtin.quad(material=Material("Checker", metallic=0.0, base_color_texture=TextureRef(0)))
    scene.textures.append(Texture(img))
    out = render_both(scene, 1, (24, 24))
    grey = {}
    for kind in out:
        mask = interior(out[kind]["effect"])[0] & (out[kind]["effect"][0, ..., 0] != 0xFF)
        assert mask.sum() > 50, f"{kind}: the quad covers too few pixels"
        base = out[kind]["baseColor"][0][mask][:, :3].astype(np.float64)
        assert base.std() < 0.02, f"{kind}: aliased texture (std {base.std():.3f})"
        grey[kind] = base.mean()
    assert 0.1 < grey["raster"] < 0.9
    assert abs(grey["rt"] - grey["raster"]) < 0.02
