"""ReSTIR DI (rayvr.passes.ReSTIRDI, `rv.graphs.hybrid(direct="restir")`) on llvmpipe, 32x32: the
mean over frames is the float64 analytic direct light under 200 point lights and an emissive quad
with reuse on and off; each eye of a stereo pair converges to its own light; a shadow stays dark
and matches RTShadows; stiff lights stay finite; the list and image dispatches agree; the history
follows the camera and resets on lighting edits; properties are checked; the compile report leaves
the pass out where no material needs shadows."""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError
from rayvr.passes import ReSTIRDI
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Camera, Light, Scene
from rayvr.xr.cameras import default_views

sys.path.insert(0, str(Path(__file__).parent))
from bsdf_reference import Bsdf  # noqa: E402

SIZE = (32, 32)
ALBEDO = 0.8
RADIUS = 4.0   # spatial_radius scaled to the 32-pixel views (the default's 30 suits full-size views)


def restir_graph(**props):
    g = rv.graphs.hybrid(preset="raw", direct="restir", restir={"spatial_radius": RADIUS, **props})
    g.mark_output("Shadows.shadowed")
    g.mark_output("GBuffer.posW")
    return g


def shadowed(r):
    return r.read_output("Shadows.shadowed")[..., :3].astype(np.float64)


def world_positions(r):
    return r.read_output("GBuffer.posW")[..., :3].astype(np.float64) + r.view_set.origin()


def mean_image(scene, graph, runs, frames, views=None):
    """The mean of Shadows.shadowed over `runs` independent renders (disjoint random streams) of
    `frames` frames each (reuse correlates a run's frames), and the world positions of the pixels."""
    total = 0.0
    for k in range(runs):
        with Renderer(scene, graph, views=views or default_views(scene, 1, SIZE), first_frame=k << 16) as r:
            for _ in range(frames):
                r.render()
                total = total + shadowed(r)
            assert r.compiled.nonfinite_counts()["Shadows"] == 0
            where = world_positions(r)
    return total / (runs * frames), where


# ---- a plane under many lights: the analytic direct light ---------------------------------------------
def many_lights_scene(n=200, seed=3) -> Scene:
    """A Lambert plane seen from above under `n` point lights of unequal power (intensity over two
    decades, random colours) and an emissive quad out of view; nothing occludes."""
    s = Scene("many_lights")
    s.add_material(builtin.lambert("Plane", (ALBEDO,) * 3, effect=rv.Effect.SHADOWS))
    s.add_object("Plane", *builtin.quad_mesh([(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)], (0, 1, 0)), "Plane")
    rng = np.random.default_rng(seed)
    for i in range(n):
        x, z = rng.uniform(-1.3, 1.3, 2)
        s.lights.append(Light("point", position=(x, rng.uniform(0.3, 1.5), z), intensity=float(10 ** rng.uniform(-2, 0)),
                              color=tuple(rng.uniform(0.2, 1.0, 3)), name=f"L{i}"))
    s.add_material(builtin.lambert("Lamp", (0.5,) * 3, emissive=(1.0, 0.8, 0.6), emissive_strength=3.0,
                                   effect=rv.Effect.SHADOWS))
    s.add_object("Lamp", *builtin.quad_mesh([(1.4, 1.2, -0.3), (2.0, 1.2, -0.3), (2.0, 1.2, 0.3), (1.4, 1.2, 0.3)],
                                            (0, -1, 0)), "Lamp")
    s.cameras.append(Camera.look_at((0, 3, 0.001), (0, 0, 0), name="Top"))
    return s


def polygon_irradiance(p, corners, n):
    """Irradiance at points p (..., 3) of normal n from a Lambertian polygon of unit radiance
    (Lambert's formula: half the sum over its edges of the angle they subtend times the cosine of
    their plane with n)."""
    u = [c - p for c in np.asarray(corners, np.float64)]
    u = [v / np.linalg.norm(v, axis=-1, keepdims=True) for v in u]
    total = np.zeros(p.shape[:-1])
    for a, b in zip(u, u[1:] + u[:1]):
        cr = np.cross(a, b)
        total += np.arccos(np.clip((a * b).sum(-1), -1, 1)) * (cr @ n) / np.linalg.norm(cr, axis=-1)
    return np.abs(total) / 2


def point_irradiance(scene, p, n):
    """rgb irradiance at p of normal n from the scene's point lights."""
    to = np.stack([L.position for L in scene.lights])[:, None, None, None] - p[None]
    d2 = (to ** 2).sum(-1)
    cos = np.clip(to @ n / np.sqrt(d2), 0, None)
    power = np.stack([np.asarray(L.color) * L.intensity for L in scene.lights])[:, None, None, None]
    return (power * (cos / d2)[..., None]).sum(0)


def lambert_plane(scene, p):
    """Float64 radiance of the Lambert plane (normal +y) at world points p: point lights and emitters."""
    n = np.array([0.0, 1.0, 0.0])
    e = point_irradiance(scene, p, n)
    for i, inst in enumerate(scene.instances):
        mesh = scene.meshes[inst.mesh]
        m = scene.materials[int(np.asarray(mesh.material_ids).flat[0])]
        if max(m.emissive) > 0:
            e += polygon_irradiance(p, mesh.positions, n)[..., None] * np.asarray(m.emissive) * m.emissive_strength
    return ALBEDO / np.pi * e


@pytest.mark.parametrize("reuse,target,visibility", [(True, "bsdf", True), (False, "bsdf", True),
                                                     (True, "cosine", True), (True, "cosine", False),
                                                     (True, "cosine", "hints")],
                         ids=["reuse", "no-reuse", "reuse-cosine-target", "reuse-fused-temporal", "reuse-hints"])
def test_many_lights_mean_is_the_analytic_direct_light(gpu, reuse, target, visibility):
    scene = many_lights_scene()
    hints = {"visibility_reuse": False, "occluded_weight": 0.05} if visibility == "hints" else {}
    props = ({"target": target, "visibility_reuse": visibility, **hints} if reuse
             else {"temporal_reuse": False, "spatial_samples": 0})
    mean, where = mean_image(scene, restir_graph(**props), runs=16, frames=64)
    want = lambert_plane(scene, where)
    # each channel within 1% (measured 0.08% with reuse, 0.1% without)
    np.testing.assert_allclose(mean.mean((0, 1, 2)), want.mean((0, 1, 2)), rtol=0.01)
    # 8x8-pixel regions: measured at most 1.4-2.8% with reuse over four seeds (their mean 1.5%:
    # noise of frames that reuse correlates), 1.0% without
    blocks = lambda a: a.reshape(4, 8, 4, 8, 3).mean((1, 3))
    np.testing.assert_allclose(blocks(mean[0]), blocks(want[0]), rtol=0.04)
    rel = np.abs(mean - want) / want
    assert np.median(rel) < 0.025   # measured 0.012 and 0.011: the noise of 1,024 frames


def test_the_auto_target_is_the_bsdfs_on_metal_and_the_cosine_on_lambert(gpu):
    """target="auto" picks each pixel's target from its surface: beside a Lambert half, a metal
    half (roughness 0.35) resamples by the BSDF. Frames match target="bsdf" on the metal and
    "cosine" on the Lambert half, the means stay RTShadows' (the halves' targets differ, and
    neighbours across the seam weigh each other's samples by their own), and the cosine target
    alone is far noisier on the metal (measured: frame error 3.8 against 0.25)."""
    scene = many_lights_scene(n=60)
    scene.add_material(rv.materials.Material("Metal", base_color=(0.9, 0.8, 0.7, 1.0), metallic=1.0, roughness=0.35,
                                             effect=rv.Effect.SHADOWS))
    scene.add_object("MetalHalf", *builtin.quad_mesh([(0, 0.001, -2), (2, 0.001, -2), (2, 0.001, 2), (0, 0.001, 2)],
                                                     (0, 1, 0)), "Metal")
    rtshadows = rv.graphs.hybrid(preset="raw", light_samples=8)
    rtshadows.mark_output("Shadows.shadowed")
    rtshadows.mark_output("GBuffer.posW")
    ref, where = mean_image(scene, rtshadows, runs=4, frames=32)
    metal = where[0][..., 0] > 0.02
    assert 0.4 < metal.mean() < 0.6
    frames, errors = {}, {}
    for target in ("bsdf", "cosine", "auto"):
        with Renderer(scene, restir_graph(target=target), views=default_views(scene, 1, SIZE)) as r:
            frames[target], err = [], []
            for frame in range(16):
                r.render()
                frames[target].append(shadowed(r)[0])
                if frame >= 8:
                    err.append(np.mean(((shadowed(r)[0] - ref[0]) ** 2 / (ref[0] ** 2 + 1e-2))[metal]))
        errors[target] = np.mean(err)
    # the same random numbers: identical frames where the targets agree
    np.testing.assert_array_equal(np.array(frames["auto"])[:, metal], np.array(frames["bsdf"])[:, metal])
    np.testing.assert_allclose(np.array(frames["auto"])[:, ~metal], np.array(frames["cosine"])[:, ~metal], rtol=1e-5)
    assert errors["cosine"] > 5 * errors["auto"]
    mean, _ = mean_image(scene, restir_graph(target="auto"), runs=8, frames=32)
    for part in (metal, ~metal):   # measured 1.016 (the reference's own noise on the metal) and 1.001
        assert abs(mean[0][part].mean() / ref[0][part].mean() - 1) < 0.03


def test_the_cosine_target_keeps_a_glossy_surfaces_mean(gpu):
    """target="cosine" resamples by Le G cos without the BSDF: on a glossy metal plane under the
    many lights (where that target is far from f cos Le G) the mean over frames is still that of
    RTShadows with 8 light samples a frame (both unbiased). Measured: means 0.9995 and 1.0073 of
    RTShadows', the median 8x8 region within 2.4% and 1.6% (the regions' noise: at most 11% and
    10% for both targets alike, so the regions' bound is on their median)."""
    scene = many_lights_scene(n=60)
    plane = scene.materials["Plane"]
    plane.metallic, plane.roughness = 1.0, 0.35
    rtshadows = rv.graphs.hybrid(preset="raw", light_samples=8)
    rtshadows.mark_output("Shadows.shadowed")
    rtshadows.mark_output("GBuffer.posW")
    ref, _ = mean_image(scene, rtshadows, runs=4, frames=32)
    got, _ = mean_image(scene, restir_graph(target="cosine"), runs=8, frames=32)
    bsdf, _ = mean_image(scene, restir_graph(), runs=8, frames=32)
    blocks = lambda a: a[0].reshape(4, 8, 4, 8, 3).mean((1, 3))
    lit = blocks(ref) > 0.02 * blocks(ref).max()
    for mean in (got, bsdf):
        assert abs(mean.mean() / ref.mean() - 1) < 0.015
        assert np.median(np.abs(blocks(mean) / np.maximum(blocks(ref), 1e-9) - 1)[lit]) < 0.04


def test_reuse_lowers_the_error_of_a_frame(gpu):
    """One frame's relMSE against the analytic light: temporal and spatial reuse each lower it
    (measured at frame 16: RTShadows 2.3, candidates alone 0.44, + spatial 0.23, + temporal 0.17,
    both 0.16)."""
    scene = many_lights_scene()
    errors = {}
    for name, graph in (("rtshadows", None), ("candidates", restir_graph(temporal_reuse=False, spatial_samples=0)),
                        ("spatial", restir_graph(temporal_reuse=False)), ("both", restir_graph())):
        if graph is None:
            graph = rv.graphs.hybrid(preset="raw")
            graph.mark_output("Shadows.shadowed")
            graph.mark_output("GBuffer.posW")
        with Renderer(scene, graph, size=SIZE) as r:
            frame = []
            for _ in range(24):
                r.render()
                want = lambert_plane(scene, world_positions(r))
                frame.append(np.mean((shadowed(r) - want) ** 2 / (want ** 2 + 1e-2)))
        errors[name] = np.mean(frame[8:])
    assert errors["candidates"] < errors["rtshadows"] / 3
    assert errors["spatial"] < 0.7 * errors["candidates"]
    assert errors["both"] < 0.5 * errors["candidates"]


# ---- stereo: each eye its own light --------------------------------------------------------------------
def two_coloured_halves() -> Scene:
    """A glossy metal plane (its light depends on the eye) under red point lights over x < 0 and
    blue ones over x > 0, seen from above."""
    s = Scene("halves")
    s.add_material(rv.materials.Material("Metal", base_color=(0.9, 0.8, 0.7, 1.0), metallic=1.0, roughness=0.35,
                                         effect=rv.Effect.SHADOWS))
    s.add_object("Metal", *builtin.quad_mesh([(-3, 0, -2), (3, 0, -2), (3, 0, 2), (-3, 0, 2)], (0, 1, 0)), "Metal")
    rng = np.random.default_rng(5)
    for i in range(24):
        side = -1 if i % 2 == 0 else 1
        s.lights.append(Light("point", position=(side * rng.uniform(0.2, 1.8), rng.uniform(0.3, 1.0), rng.uniform(-1, 1)),
                              intensity=float(rng.uniform(0.2, 1.0)), color=(1.0, 0.1, 0.05) if side < 0 else (0.05, 0.2, 1.0)))
    s.cameras.append(Camera.look_at((0, 2.2, 0.001), (0, 0, 0), name="Top"))
    return s


def glossy_plane(scene, p, eye):
    """Float64 radiance of the plane at world points p seen from `eye` (bsdf_reference)."""
    bsdf = Bsdf(base_color=(0.9, 0.8, 0.7), metallic=1.0, roughness=0.35)
    v = eye - p
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    out = np.zeros(p.shape)
    for L in scene.lights:
        to = L.position - p
        d2 = (to ** 2).sum(-1, keepdims=True)
        l = to / np.sqrt(d2)
        out += bsdf.eval(v, l, (0.0, 1.0, 0.0)) * np.asarray(L.color) * L.intensity / d2
    return out


@pytest.mark.parametrize("share_views", [True, False], ids=["shared", "apart"])
def test_each_eye_converges_to_its_own_light(gpu, share_views):
    """Eyes 1.2 m apart see mostly the red (left eye) and the blue (right eye) half, both the
    middle, with highlights where each eye sees them: each eye's mean is its own float64 image,
    so no light (or highlight) of one eye reached the other."""
    scene = two_coloured_halves()
    views = default_views(scene, 2, SIZE, ipd=1.2)
    mean, where = mean_image(scene, restir_graph(share_views=share_views), runs=8, frames=64, views=views)
    red_share = []
    for v in range(2):
        want = glossy_plane(scene, where[v], views[v].pose.position)
        np.testing.assert_allclose(mean[v].mean((0, 1)), want.mean((0, 1)), rtol=0.015)   # measured <= 0.7%
        lum = lambda a: a @ [0.2126, 0.7152, 0.0722]
        rel = np.abs(lum(mean[v]) - lum(want)) / lum(want)
        assert np.median(rel) < 0.035   # measured 0.012-0.017
        red_share.append(want[..., 0].sum() / want[..., 2].sum())
    assert red_share[0] > 2 * red_share[1]   # the eyes do see differently lit surfaces


def test_views_share_samples_only_where_they_see_one_surface(gpu):
    """With sharing, the right eye's frames are less noisy than alone (it reuses the left eye's
    reservoirs where both see the plane)."""
    scene = two_coloured_halves()
    views = default_views(scene, 2, SIZE, ipd=0.1)
    errors = {}
    for share in (True, False):
        with Renderer(scene, restir_graph(share_views=share, spatial_samples=0, temporal_reuse=False), views=views) as r:
            err = []
            for _ in range(12):
                r.render()
                want = glossy_plane(scene, world_positions(r)[1], views[1].pose.position)
                err.append(np.mean((shadowed(r)[1] - want) ** 2 / (want ** 2 + 1e-2)))
        errors[share] = np.mean(err)
    assert errors[True] < 0.8 * errors[False]


# ---- shadows -------------------------------------------------------------------------------------------
def box_shadow_scene() -> Scene:
    """A box on a floor under a point light and an emissive quad, seen at an angle: a hard and a
    soft shadow, and an umbra that neither light reaches."""
    s = Scene("box_shadow")
    s.add_material(builtin.lambert("Floor", (0.8,) * 3, effect=rv.Effect.SHADOWS))
    s.add_object("Floor", *builtin.quad_mesh([(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)], (0, 1, 0)), "Floor")
    s.add_material(builtin.lambert("Box", (0.6, 0.3, 0.2), effect=rv.Effect.SHADOWS))
    s.add_object("Box", *builtin.box((-0.3, 0.0, -0.3), (0.3, 0.6, 0.3)), "Box")
    s.lights.append(Light("point", position=(0.4, 1.5, 0.3), intensity=3.0, name="Point"))
    s.add_material(builtin.lambert("Lamp", (0.5,) * 3, emissive=(1.0, 0.9, 0.8), emissive_strength=4.0,
                                   effect=rv.Effect.SHADOWS))
    s.add_object("Lamp", *builtin.quad_mesh([(-0.9, 1.6, -0.5), (-0.4, 1.6, -0.5), (-0.4, 1.6, 0.0), (-0.9, 1.6, 0.0)],
                                            (0, -1, 0)), "Lamp")
    s.cameras.append(Camera.look_at((0.0, 2.6, 2.2), (0, 0, 0), yfov_deg=50, name="Camera"))
    return s


@pytest.fixture(scope="module")
def rtshadows_reference(gpu):
    """RTShadows with 16 light samples, 256 frames: the shadowed direct light converged."""
    scene = box_shadow_scene()
    g = rv.graphs.hybrid(preset="raw", light_samples=16)
    g.mark_output("Shadows.shadowed")
    g.mark_output("GBuffer.posW")
    return mean_image(scene, g, runs=4, frames=64)[0]


NO_RAY = {"visibility_reuse": False}
HINTS = {"visibility_reuse": False, "occluded_weight": 0.05}


@pytest.mark.parametrize("props,biased", [(NO_RAY, False), ({}, True), (HINTS, False),
                                          ({**HINTS, "spatial_samples": 0}, False)],
                         ids=["unbiased", "visibility-reuse", "visibility-hints", "visibility-hints-temporal"])
def test_a_shadow_stays_dark_and_matches_rtshadows(gpu, rtshadows_reference, props, biased):
    scene = box_shadow_scene()
    ref = rtshadows_reference
    mean, _ = mean_image(scene, restir_graph(**props), runs=8, frames=64)
    umbra = ref.max(-1) == 0
    assert umbra.sum() > 50 and mean[umbra].max() == 0.0   # no light through the box
    blocks = lambda a: a[0].reshape(4, 8, 4, 8, 3).mean((1, 3))
    block_error = np.abs(blocks(mean) / np.maximum(blocks(ref), 1e-6) - 1)[blocks(ref) > 0.01].max()
    ratio = mean.mean() / ref.mean()
    if biased:
        # the accepted bias (restir_di.py): darker within the spatial radius of a shadow's edge,
        # never brighter (measured: mean 0.990, 8x8 regions at most 5% off)
        assert 0.97 < ratio < 1.003 and block_error < 0.08
    else:   # unbiased (measured: mean 1.0008, regions within 0.9%; with hints 1.0006 and 1.0013, 0.8% and 1.2%)
        assert abs(ratio - 1) < 0.005 and block_error < 0.02


def test_visibility_hints_steer_samples_to_the_light_a_pixel_sees(gpu, rtshadows_reference):
    """Beside the box the point light is occluded and the lamp is not: without a visibility ray,
    hints (the last shading ray's verdicts) make candidates and history favour the lamp."""
    scene = box_shadow_scene()
    ref = rtshadows_reference
    errors = {}
    for weight in (1.0, 0.05):
        props = {**NO_RAY, "spatial_samples": 0, "candidates": 2, "occluded_weight": weight}
        with Renderer(scene, restir_graph(**props), views=default_views(scene, 1, SIZE)) as r:
            err = []
            for frame in range(24):
                r.render()
                if frame >= 16:
                    err.append(np.mean((shadowed(r) - ref) ** 2 / (ref ** 2 + 1e-2)))
            report = r.report()
        errors[weight] = np.mean(err)
        assert ("Shadows.hints" in {res.name for res in report.resources}) == (weight < 1.0)
    assert errors[0.05] < 0.5 * errors[1.0]   # measured 0.0102 against 0.0294


def test_a_single_lights_hard_shadow_is_exact_with_visibility_reuse(gpu):
    """One point light: every pixel's estimate is exact, in and beside the box's shadow, frame
    after frame (an empty neighbour is not reused: its shadow does not darken its surround)."""
    scene = builtin.box_on_plane(light_height=1.0)
    scene.cameras[:] = [Camera.look_at((0.0, 2.5, 2.0), (0, 0, 0), yfov_deg=50)]
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    g = rv.graphs.hybrid(preset="raw")
    g.mark_output("Shadows.shadowed")
    with Renderer(scene, g, size=SIZE) as r:
        r.render()
        want = shadowed(r)
    with Renderer(scene, restir_graph(), size=SIZE) as r:
        for _ in range(8):
            r.render()
            np.testing.assert_allclose(shadowed(r), want, rtol=2e-3, atol=1e-4)
    assert (want.max(-1) == 0).sum() > 20


def test_reflections_pixels_share_the_specular_light_as_rtshadows_does(gpu):
    """A glossy REFLECTIONS floor under the quad and the point light: RTReflections traces its
    specular lobe and the two share the lobe's light by the power heuristic; the composite's mean
    is RTShadows' (measured: 0.9987, regions within the reflections' own noise, 3.3%)."""
    scene = box_shadow_scene()
    floor = scene.materials["Floor"]
    floor.metallic, floor.roughness, floor.effect = 1.0, 0.25, rv.Effect.REFLECTIONS
    means = []
    for graph in (rv.graphs.hybrid(preset="raw", light_samples=8), rv.graphs.hybrid(preset="raw", direct="restir", restir={"spatial_radius": RADIUS})):
        total = 0.0
        for k in range(4):
            with Renderer(scene, graph, size=SIZE, first_frame=k << 16) as r:
                for _ in range(64):
                    r.render()
                    total = total + r.read_output("Composite.color")[..., :3].astype(np.float64)
        means.append(total / 256)
    ref, got = means
    assert abs(got.mean() / ref.mean() - 1) < 0.01
    blocks = lambda a: a[0].reshape(4, 8, 4, 8, 3).mean((1, 3))
    assert np.abs(blocks(got) / np.maximum(blocks(ref), 1e-6) - 1)[blocks(ref) > 0.01].max() < 0.06


def test_bound_probe_inputs_add_their_light_as_in_rtshadows(gpu):
    from rayvr.passes.probe_gi import inputs as probe_inputs

    scene = box_shadow_scene()
    means = []
    for direct in (None, "restir"):
        g = rv.graphs.hybrid(preset="raw", gi="probes", direct=direct, light_samples=4, restir={"spatial_radius": RADIUS} if direct else None)
        probe_inputs.wire(g, "Probes", "Shadows")
        g.mark_output("Shadows.shadowed")
        with Renderer(scene, g, size=SIZE) as r:
            total = 0.0
            for _ in range(64):
                r.render()
                total = total + shadowed(r)
            assert r.report().defines["Shadows"]["PROBE_GI"] == 1
        means.append(total / 64)
    assert abs(means[1].mean() / means[0].mean() - 1) < 0.02


# ---- robustness ----------------------------------------------------------------------------------------
def test_stiff_lights_grazing_angles_and_zero_area_emitters_stay_finite(gpu):
    s = Scene("stiff")
    s.add_material(builtin.lambert("Floor", (0.8,) * 3, effect=rv.Effect.SHADOWS))
    s.add_object("Floor", *builtin.quad_mesh([(-50, 0, -50), (50, 0, -50), (50, 0, 50), (-50, 0, 50)], (0, 1, 0)), "Floor")
    s.add_material(rv.materials.Material("Gloss", base_color=(1, 1, 1, 1), metallic=1.0, roughness=0.01,
                                         effect=rv.Effect.REFLECTIONS))
    s.add_object("Gloss", *builtin.quad_mesh([(-1, 0.01, 1), (1, 0.01, 1), (1, 0.01, 3), (-1, 0.01, 3)], (0, 1, 0)), "Gloss")
    s.add_material(builtin.lambert("Bright", (0.5,) * 3, emissive=(1.0, 1.0, 1.0), emissive_strength=1e6,
                                   effect=rv.Effect.SHADOWS))
    s.add_object("Bright", np.array([[0, 1, 0], [1e-9, 1, 0], [0, 1, 1e-9], [0, 2, 0], [0, 2, 0], [0.1, 2, 0]], np.float32),
                 np.array([[0, 1, 2], [3, 4, 5]], np.uint32), "Bright")   # a tiny and a zero-area emitter
    s.lights.append(Light("point", position=(0.0, 1e-4, -2.0), intensity=1e6, name="Grazing"))
    s.lights.append(Light("point", position=(1.0, 0.5, 0.0), intensity=1e-6, name="Faint"))
    s.lights.append(Light("spot", position=(-1.0, 0.3, 0.0), direction=(0, -1, 0), intensity=1e6, name="Spot"))
    s.lights.append(Light("directional", direction=(0.0, -1e-3, -1.0), intensity=1e3, name="LowSun"))
    s.cameras.append(Camera.look_at((0.0, 0.05, 4.0), (0, 0, -10), name="Grazing"))
    for props in ({}, {"visibility_reuse": False, "candidates": 1}):
        with Renderer(s, restir_graph(**props), size=SIZE) as r:
            for _ in range(6):
                r.render()
                out = shadowed(r)
                assert np.isfinite(out).all()
            counts = r.compiled.nonfinite_counts()
        assert counts["Shadows"] == 0, counts
        assert out.max() > 0


# ---- the dispatch forms, the history -------------------------------------------------------------------
def test_the_list_and_image_dispatches_light_the_same_pixels_alike(gpu):
    scene = box_shadow_scene()
    images = []
    for mode in ("image", "list"):
        with Renderer(scene, restir_graph(dispatch_mode=mode), views=default_views(scene, 2, SIZE)) as r:
            for _ in range(3):
                r.render()
            images.append(shadowed(r))
    np.testing.assert_array_equal(images[0], images[1])


def test_history_follows_the_camera_and_resets_on_lighting_edits(gpu):
    import dataclasses

    from rayvr.xr.views import Pose, ViewSet

    scene = many_lights_scene(n=20)
    views = default_views(scene, 1, SIZE)
    with Renderer(scene, restir_graph(), views=views) as r:
        r.render()
        restir = r.compiled.passes["Shadows"]
        assert restir.history_valid
        moved = dataclasses.replace(views[0], pose=Pose(views[0].pose.position + [0.05, 0.0, 0.0],
                                                        views[0].pose.orientation))
        r.render(ViewSet([moved], previous=views))
        assert restir.resets == 0
        scene.lights[0].intensity = 5.0
        r.render()
        assert restir.resets == 1
        restir.reset()
        assert not restir.history_valid
        r.render()
        assert restir.history_valid and restir.resets == 1


def test_a_lighting_edit_shows_at_once(gpu):
    """The frame after a light is turned off has none of its light (no history of it)."""
    scene = many_lights_scene(n=1)
    scene.lights[0].intensity = 2.0
    scene.lights.append(Light("point", position=(0.0, 1.0, 0.0), intensity=0.5, name="Other"))
    with Renderer(scene, restir_graph(), size=SIZE) as r:
        for _ in range(4):
            r.render()
        scene.lights[0].intensity = 0.0
        r.render()
        got, where = shadowed(r), world_positions(r)
    scene.lights[0].intensity = 0.0
    want = lambert_plane(scene, where)
    np.testing.assert_allclose(got.mean(), want.mean(), rtol=0.05)


# ---- properties, options, the compile report ------------------------------------------------------------
def test_properties_round_trip_and_bad_values_name_pass_and_key():
    p = ReSTIRDI(candidates=4, target="cosine", spatial_samples=2, spatial_radius=12, share_views=False)
    # the viewer's property panel offers the pass's choices (its own and the ray passes')
    assert tuple(ReSTIRDI.CHOICES["target"]) == ("bsdf", "cosine", "auto") and "dispatch_mode" in ReSTIRDI.CHOICES
    props = p.get_properties()
    assert props["spatial_radius"] == 12.0 and isinstance(props["spatial_radius"], float)
    assert ReSTIRDI(json.loads(json.dumps(props))).get_properties() == props
    g = rv.graphs.hybrid(preset="raw", direct="restir", restir={"candidates": 16})
    again = rv.RenderGraph.from_dict(json.loads(json.dumps(g.to_dict())))
    assert type(again.passes["Shadows"]) is ReSTIRDI and again.passes["Shadows"].candidates == 16
    scope = {}
    exec(g.to_script(), scope)   # the Falcor-style script builds it again
    assert scope["hybrid"].passes["Shadows"].get_properties() == g.passes["Shadows"].get_properties()
    bad = [("candidates", 0, r"'candidates' must be an integer from 1 to 64"),
           ("candidates", 2.5, r"'candidates' must be an integer"),
           ("spatial_samples", 17, r"'spatial_samples' must be an integer from 0 to 16"),
           ("max_history_m", 0, r"'max_history_m' must be an integer from 1"),
           ("spatial_radius", 0.5, r"'spatial_radius' must be from 1 to 256 pixels"),
           ("target", "brdf", r"'target' is 'brdf'; use 'bsdf' \(p_hat = f cos Le G\), 'cosine' \(.*\) or 'auto'"),
           ("visibility_reuse", 1, r"'visibility_reuse' must be true or false"),
           ("occluded_weight", 0.0, r"'occluded_weight' must be a number in \(0, 1\]"),
           ("occluded_weight", 1.5, r"'occluded_weight' must be a number in \(0, 1\]"),
           ("dispatch_mode", "both", r"'dispatch_mode' is 'both'"),
           ("tile", [0, 4], r"'tile' must be \[x, y\]")]
    for key, value, message in bad:
        with pytest.raises(OptionError, match=r"^pass ReSTIRDI: property " + message):
            ReSTIRDI({key: value})
    with pytest.raises(OptionError, match=r"unknown property 'candidate'.*did you mean 'candidates'"):
        ReSTIRDI(candidate=4)
    with pytest.raises(OptionError, match=r"hybrid\(direct='restr'\): use None \('none'\) or 'restir'"):
        rv.graphs.hybrid(preset="raw", direct="restr")
    with pytest.raises(OptionError, match=r"hybrid\(restir=...\): ReSTIR settings need direct='restir'"):
        rv.graphs.hybrid(preset="raw", restir={"candidates": 4})


def test_the_report_leaves_the_pass_out_where_no_material_needs_shadows(gpu):
    scene = many_lights_scene(n=3)
    for m in scene.materials:
        m.effect = rv.Effect.RASTER
    with Renderer(scene, rv.graphs.hybrid(preset="raw", direct="restir"), size=(8, 8)) as r:
        report = r.report()
    assert report.pruned["Shadows"] == "no material uses SHADOWS or above"
    assert not any(res.name.startswith("Shadows.") for res in report.resources)
    scene.materials["Plane"].effect = rv.Effect.SHADOWS
    with Renderer(scene, rv.graphs.hybrid(preset="raw", direct="restir"), views=2, size=(8, 8)) as r:
        report = r.report()
        restir = r.compiled.passes["Shadows"]
    assert isinstance(restir, ReSTIRDI) and "Shadows" in report.order
    defines = report.defines["Shadows"]
    assert defines["RESTIR_CANDIDATES"] == 8 and defines["SCENE_HAS_ENVIRONMENT"] == 0
    names = {res.name for res in report.resources if res.name.startswith("Shadows.")}
    assert {"Shadows.reservoirs0", "Shadows.reservoirs1", "Shadows.history0", "Shadows.surface1"} <= names
    assert restir.stages(2) == ("candidates", "temporal", "spatial")
    assert ReSTIRDI(temporal_reuse=False, spatial_samples=0).stages(1) == ("candidates",)
    assert ReSTIRDI(temporal_reuse=False, spatial_samples=0).stages(2) == ("candidates", "spatial")
    # without visibility rays the candidates' kernel does the temporal reuse: no candidates image
    with Renderer(scene, rv.graphs.hybrid(preset="raw", direct="restir", restir={"visibility_reuse": False}),
                  views=2, size=(8, 8)) as r:
        report = r.report()
        assert r.compiled.passes["Shadows"].stages(2) == ("candidates", "spatial")
    names = {res.name for res in report.resources if res.name.startswith("Shadows.")}
    assert "Shadows.reservoirs0" not in names and {"Shadows.history0", "Shadows.reservoirs1"} <= names
    assert report.defines["Shadows"]["RESTIR_FUSED_TEMPORAL"] == 1


def test_the_command_line_offers_restir():
    from rayvr.cli.main import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    options = {a.dest: a for a in sub.choices["render"]._actions}
    assert options["direct"].choices == ("none", "restir")
    args = build_parser().parse_args(["render", "cornell_box", "--direct", "restir", "--out", "x.png"])
    from rayvr.cli.render import build_graph

    graph = build_graph(args, 0.0, False)
    assert type(graph.passes["Shadows"]) is ReSTIRDI
