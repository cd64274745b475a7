"""alphaMode BLEND as stochastic transparency: a surface of alpha a is there for a ray or a G-buffer
fragment with probability a, decided anew each frame (stratified over frames), so the mean over
frames is a * front + (1 - a) * behind and a shadow through it keeps 1 - a of the light.

Scenes are emitters and Lambert planes (f = rho / pi exactly; black ones reflect nothing), so every
frame's pixel is one of two closed-form values and the mean over N frames counts how often the
veil was hit. Tolerances: decisions at a pixel are stratified over frames (the Owen-scrambled van
der Corput sequence of the frame index), so a pixel's count over N frames is within 2 of a * N
(PER_PIXEL); the image mean is also held to 4 binomial standard errors of N x pixels independent
draws, sqrt(a (1 - a) / (N P)) x |front - behind|, what unstratified decisions would need.
"""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.renderer import Renderer
from rayvr.scene.builtin import lambert, quad_mesh
from rayvr.scene.model import Environment, Light, Scene
from rayvr.xr.cameras import look_at
from rayvr.xr.views import Fov, View, ViewSet

SIZE = 24
FRAMES = 32
ALPHA = 0.3
FRONT, BEHIND = 3.0, 1.0          # the veil's and the wall's emitted radiance
HALF_RTOL = 2e-3                  # float16 targets
PT = "Accumulate.dst"
HYBRID = "Composite.color"


def view_set(eye, target, fov=40.0):
    return ViewSet([View(look_at(eye, target), Fov.symmetric(fov, 1.0), SIZE, SIZE, 0.01, 100.0)])


def blend_material(name, alpha, rgb=(0.0, 0.0, 0.0), **kw):
    m = lambert(name, rgb, **kw)
    m.base_color = (*rgb, alpha)
    m.alpha_mode = "BLEND"
    return m


def veil_scene(alpha=ALPHA, effect=rv.Effect.RASTER) -> Scene:
    """An emissive veil (radiance FRONT, alpha `alpha`, black: it reflects nothing) at z = 0 in
    front of an emissive black wall (radiance BEHIND) at z = -1, under a black sky."""
    s = Scene("veil")
    s.add_material(blend_material("Veil", alpha, emissive=(1.0, 1.0, 1.0), emissive_strength=FRONT, effect=effect))
    s.add_material(lambert("Wall", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0), emissive_strength=BEHIND,
                           effect=effect))
    s.add_object("Veil", *quad_mesh([[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]], (0, 0, 1)), "Veil")
    s.add_object("Wall", *quad_mesh([[-3, -3, -1], [3, -3, -1], [3, 3, -1], [-3, 3, -1]], (0, 0, 1)), "Wall")
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    return s


VEIL_VIEWS = ((0.0, 0.0, 3.0), (0.0, 0.0, 0.0))


def plane_hits(views, plane_z=None, plane_y=None):
    """(h, w, 2) where each pixel-centre ray of view 0 meets the plane z = plane_z (x, y) or
    y = plane_y (x, z); rows bottom-up."""
    v = views[0]
    out = np.zeros((v.height, v.width, 2))
    for j in range(v.height):
        for i in range(v.width):
            o, d = v.primary_ray((i + 0.5, j + 0.5))
            if plane_z is not None:
                p = o + d * (plane_z - o[2]) / d[2]
                out[j, i] = p[0], p[1]
            else:
                t = (plane_y - o[1]) / d[1]
                p = o + d * t
                out[j, i] = (p[0], p[2]) if t > 0 else (np.inf, np.inf)
    return out


def veil_masks(views):
    """Pixels well inside the veil's square and pixels well outside it (they see the wall)."""
    xy = np.abs(plane_hits(views, plane_z=0.0)).max(-1)
    return xy < 0.45, xy > 0.55


def frames_of(scene, graph, views, pin, frames=FRAMES):
    """Each frame's rgb of `pin` (frames, h, w, 3), float64, checked finite and >= 0."""
    out = []
    with Renderer(scene, graph, views=views) as r:
        for _ in range(frames):
            r.render()
            img = r.read_output(pin).astype(np.float64)[0, ..., :3]
            assert np.isfinite(img).all() and (img >= 0).all()
            out.append(img)
    return np.stack(out)


def path_traced(spp=1):
    g = rv.graphs.path_traced(samples_per_pixel=spp, max_bounces=1)
    g.update_pass("PathTracer", {"pixel_jitter": False})
    return g


def assert_blend_mean(mean, inside, outside, a, front, behind, frames, rtol, what):
    """mean's veil pixels are a * front + (1 - a) * behind (per pixel within 2 decisions of N, the
    image mean within 4 binomial standard errors), the others `behind`."""
    want = a * front + (1 - a) * behind
    step = abs(front - behind)
    v = mean[inside][:, 0]
    assert inside.sum() > 20 and outside.sum() > 20
    per_pixel = np.abs(v - want).max()
    assert per_pixel <= 2 * step / frames + rtol * max(front, behind), \
        f"{what}: a veil pixel's mean is off {want:.4f} by {per_pixel:.4f} (> 2 of {frames} decisions)"
    se = math.sqrt(a * (1 - a) / (frames * v.size)) * step
    assert abs(v.mean() - want) <= 4 * se + rtol * max(front, behind), \
        f"{what}: veil mean {v.mean():.5f}, want {want:.5f} +- {4 * se:.5f} (4 binomial s.e.)"
    np.testing.assert_allclose(mean[outside], behind, rtol=rtol, err_msg=f"{what}: the wall around the veil")


# ---- the veil's colour over the wall --------------------------------------------------------------
@pytest.mark.parametrize("graph", ["pt", "raster", "rt"])
def test_mean_over_frames_is_the_alpha_blend_of_the_veil_over_the_wall(gpu, graph):
    views = view_set(*VEIL_VIEWS)
    inside, outside = veil_masks(views)
    scene = veil_scene()
    if graph == "pt":
        with Renderer(scene, path_traced(), views=views) as r:
            for _ in range(FRAMES):
                r.render()
            mean = r.read_output(PT).astype(np.float64)[0, ..., :3]
        rtol = 1e-5
    else:
        imgs = frames_of(scene, rv.graphs.hybrid(preset="raw", gbuffer=graph), views, HYBRID)
        # every frame shows either the veil or the wall at a pixel, never a mixture
        v = imgs[:, inside, 0]
        assert (np.isclose(v, FRONT, rtol=HALF_RTOL) | np.isclose(v, BEHIND, rtol=HALF_RTOL)).all()
        mean, rtol = imgs.mean(0), HALF_RTOL
    assert_blend_mean(mean, inside, outside, ALPHA, FRONT, BEHIND, FRAMES, rtol, graph)


def test_samples_of_one_frame_are_stratified_too(gpu):
    """32 samples per pixel in one frame of the path tracer: the same blend (the sample index runs
    over a frame's samples as over frames)."""
    views = view_set(*VEIL_VIEWS)
    inside, outside = veil_masks(views)
    with Renderer(veil_scene(), path_traced(spp=32), views=views) as r:
        r.render()
        mean = r.read_output(PT).astype(np.float64)[0, ..., :3]
    assert_blend_mean(mean, inside, outside, ALPHA, FRONT, BEHIND, 32, 1e-5, "pt 32 spp")


def test_raster_and_rt_gbuffers_make_the_same_decisions(gpu):
    """GBufferRaster and GBufferRT draw the veil at the same pixels in the same frames (one key per
    pixel, triangle and frame): the frames agree away from the quad's diagonal and edges, where
    the two may see different triangles. Independent decisions would agree at ~58% of them."""
    views = view_set(*VEIL_VIEWS)
    inside, _ = veil_masks(views)
    xy = plane_hits(views, plane_z=0.0)
    off_diagonal = inside & (np.abs(xy[..., 0] - xy[..., 1]) > 0.05) & (np.abs(xy[..., 0] + xy[..., 1]) > 0.05)
    scene = veil_scene()
    a = frames_of(scene, rv.graphs.hybrid(preset="raw", gbuffer="raster"), views, HYBRID, frames=8)[:, off_diagonal, 0]
    b = frames_of(scene, rv.graphs.hybrid(preset="raw", gbuffer="rt"), views, HYBRID, frames=8)[:, off_diagonal, 0]
    same = np.isclose(a, b, rtol=HALF_RTOL).mean()
    assert same > 0.97, f"raster and RT G-buffers agree at {same:.1%} of the veil's pixels x frames"


@pytest.mark.parametrize("alpha, want", [(1.0, FRONT), (0.0, BEHIND)])
@pytest.mark.parametrize("graph", ["pt", "raster", "rt"])
def test_alpha_one_is_opaque_and_alpha_zero_invisible_in_every_frame(gpu, graph, alpha, want):
    views = view_set(*VEIL_VIEWS)
    inside, outside = veil_masks(views)
    g = path_traced() if graph == "pt" else rv.graphs.hybrid(preset="raw", gbuffer=graph)
    pin = PT if graph == "pt" else HYBRID
    imgs = frames_of(veil_scene(alpha), g, views, pin, frames=6)
    np.testing.assert_allclose(imgs[:, inside], want, rtol=HALF_RTOL)
    np.testing.assert_allclose(imgs[:, outside], BEHIND, rtol=HALF_RTOL)


def test_an_alpha_mode_set_after_the_upload_reaches_the_rays(gpu):
    """The BVH's triangle slots carry their material's alpha mode, so that an opaque hit reads no
    material: a mode changed after the upload is what the next frame's rays see. The veil starts
    OPAQUE (FRONT in every frame; a BLEND quad out of view keeps the scene's BLEND code) and,
    made BLEND, gives the blend."""
    views = view_set(*VEIL_VIEWS)
    inside, _ = veil_masks(views)
    scene = veil_scene()
    scene.materials["Veil"].alpha_mode = "OPAQUE"
    scene.add_material(blend_material("Aside", ALPHA))
    scene.add_object("Aside", *quad_mesh([[20, 0, 0], [21, 0, 0], [21, 1, 0], [20, 1, 0]], (0, 0, 1)), "Aside")
    with Renderer(scene, path_traced(), views=views) as r:
        for _ in range(2):
            r.render()
            img = r.read_output(PT).astype(np.float64)[0, ..., :3]
            np.testing.assert_allclose(img[inside], FRONT, rtol=1e-5, err_msg="an OPAQUE veil")
        scene.materials["Veil"].alpha_mode = "BLEND"
        for _ in range(FRAMES):
            r.render()
        v = r.read_output(PT).astype(np.float64)[0, ..., 0][inside]
    # these frames do not start the stratified sequence: only the image mean is held (4 binomial s.e.)
    want, se = ALPHA * FRONT + (1 - ALPHA) * BEHIND, math.sqrt(ALPHA * (1 - ALPHA) / (FRAMES * v.size)) * (FRONT - BEHIND)
    assert abs(v.mean() - want) <= 4 * se, f"the veil made BLEND: mean {v.mean():.4f}, want {want:.4f} +- {4 * se:.4f}"


@pytest.mark.parametrize("effect", [rv.Effect.RASTER, rv.Effect.SHADOWS])
def test_light_sampled_from_a_blend_emitter_is_alpha_times_its_light(gpu, effect):
    """A double-sided emissive veil lighting a grey wall: light sampling weighs a BLEND emitter by
    its alpha (what the rays that hit it see on average), so the wall around the veil under alpha
    0.3 is 0.3 x its light under alpha 1, frame by frame (the same light samples)."""
    views = view_set(*VEIL_VIEWS)
    _, outside = veil_masks(views)
    lit = {}
    for alpha in (1.0, ALPHA):
        s = veil_scene(alpha, effect)
        s.materials["Wall"].base_color = (0.8, 0.8, 0.8, 1.0)
        s.materials["Wall"].emissive = (0.0, 0.0, 0.0)
        s.materials["Veil"].double_sided = True
        lit[alpha] = frames_of(s, rv.graphs.hybrid(preset="raw", gbuffer="rt"), views, HYBRID, frames=2)[:, outside]
    assert (lit[1.0] > 1e-3).mean() > 0.9, "the veil lights the wall around it"
    np.testing.assert_allclose(lit[ALPHA], ALPHA * lit[1.0], rtol=2 * HALF_RTOL, atol=1e-6)


# ---- shadows through the veil -----------------------------------------------------------------------
RHO, E = 0.4, 2.0


def shadow_scene(alpha=ALPHA, effect=rv.Effect.SHADOWS) -> Scene:
    """A Lambert floor (albedo RHO) at y = 0 under a sun of illuminance E straight down, with a black
    veil of alpha `alpha` 1 m above [-0.5, 0.5]^2; the camera sees the floor under the veil from the
    side, below the veil's height."""
    s = Scene("shadow")
    s.add_material(lambert("Floor", (RHO,) * 3, effect=effect))
    s.add_material(blend_material("Veil", alpha, effect=effect, double_sided=True))
    s.add_object("Floor", *quad_mesh([[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], (0, 1, 0)), "Floor")
    s.add_object("Veil", *quad_mesh([[-0.5, 1, -0.5], [0.5, 1, -0.5], [0.5, 1, 0.5], [-0.5, 1, 0.5]], (0, 1, 0)),
                 "Veil")
    s.lights.append(Light("directional", direction=(0.0, -1.0, 0.0), intensity=E))
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    return s


SHADOW_VIEWS = ((0.0, 0.8, 1.5), (0.0, 0.0, 0.0))


@pytest.mark.parametrize("graph, effect", [("pt", rv.Effect.SHADOWS), ("raster", rv.Effect.SHADOWS),
                                           ("rt", rv.Effect.SHADOWS), ("raster", rv.Effect.PATH_TRACED)])
def test_a_shadow_through_the_veil_keeps_one_minus_alpha_of_the_light(gpu, graph, effect):
    """The floor under the veil gets (1 - alpha) E: in the path tracer, and in the hybrid's ray
    traced shadows and path-traced pixels."""
    views = view_set(*SHADOW_VIEWS)
    xz = np.abs(plane_hits(views, plane_y=0.0)).max(-1)
    inside, outside = xz < 0.45, (xz > 0.55) & (xz < 3.5)
    lit = RHO / math.pi * E
    scene = shadow_scene(effect=effect)
    if graph == "pt":
        with Renderer(scene, path_traced(), views=views) as r:
            for _ in range(FRAMES):
                r.render()
            mean, rtol = r.read_output(PT).astype(np.float64)[0, ..., :3], 1e-5
    else:
        imgs = frames_of(scene, rv.graphs.hybrid(preset="raw", gbuffer=graph), views, HYBRID)
        # the hybrid accumulates its path-traced pixels: the last frame is their mean
        mean, rtol = (imgs[-1] if effect == rv.Effect.PATH_TRACED else imgs.mean(0)), HALF_RTOL
    assert_blend_mean(mean, inside, outside, ALPHA, 0.0, lit, FRAMES, rtol, f"{graph} {effect.name}")
    # alpha 1 casts a full shadow, alpha 0 none, in the first frame already
    for alpha, want in ((1.0, 0.0), (0.0, lit)):
        g = path_traced() if graph == "pt" else rv.graphs.hybrid(preset="raw", gbuffer=graph)
        img = frames_of(shadow_scene(alpha, effect), g, views, PT if graph == "pt" else HYBRID, frames=1)[0]
        np.testing.assert_allclose(img[inside], want, rtol=HALF_RTOL, atol=1e-6)


def two_veils_scene():
    scene = shadow_scene()
    scene.add_material(blend_material("Veil2", 0.5, effect=rv.Effect.SHADOWS, double_sided=True))
    scene.add_object("Veil2", *quad_mesh([[-0.6, 1.3, -0.6], [0.6, 1.3, -0.6], [0.6, 1.3, 0.6], [-0.6, 1.3, 0.6]],
                                         (0, 1, 0)), "Veil2")
    return scene


@pytest.mark.parametrize("graph", ["raster", "rt"])
def test_the_hybrids_shadow_rays_take_the_veils_transmittance_in_every_frame(gpu, graph):
    """The hybrid's shadow rays multiply (1 - alpha) over the BLEND surfaces they pass instead of
    deciding each by a coin: under two stacked veils (alpha 0.3 and 0.5) the floor gets
    0.7 x 0.5 of the light in every pixel of every frame, no speckle."""
    views = view_set(*SHADOW_VIEWS)
    xz = np.abs(plane_hits(views, plane_y=0.0)).max(-1)
    inside = xz < 0.45
    imgs = frames_of(two_veils_scene(), rv.graphs.hybrid(preset="raw", gbuffer=graph), views, HYBRID, frames=4)
    want = (1 - ALPHA) * 0.5 * RHO / math.pi * E
    np.testing.assert_allclose(imgs[:, inside], want, rtol=HALF_RTOL, atol=1e-6)


@pytest.mark.parametrize("roulette", [0.5, 1.0])
def test_the_shadows_blend_roulette_keeps_the_mean_over_frames(gpu, roulette):
    """RTShadows(blend_roulette): below the threshold a shadow ray goes on by Russian roulette, so a
    frame's pixel is 0 or a share of the light, and the mean over frames is still 0.7 x 0.5 of it
    (the decisions are stratified over frames, so the mean is held to FRAMES-draw binomial noise)."""
    views = view_set(*SHADOW_VIEWS)
    xz = np.abs(plane_hits(views, plane_y=0.0)).max(-1)
    inside = xz < 0.45
    g = rv.graphs.hybrid(preset="raw", gbuffer="rt")
    g.update_pass("Shadows", {"blend_roulette": roulette})
    imgs = frames_of(two_veils_scene(), g, views, HYBRID)
    lit, p = RHO / math.pi * E, (1 - ALPHA) * 0.5
    assert (imgs[:, inside] < 0.01 * lit).any(), "some shadow rays end by roulette"
    noise = math.sqrt(p * (1 - p) / (FRAMES * inside.sum())) * lit / roulette
    np.testing.assert_allclose(imgs[:, inside].mean(), p * lit, atol=4 * noise)
    with pytest.raises(rv.errors.OptionError, match="blend_roulette"):
        g.update_pass("Shadows", {"blend_roulette": 1.5})


# ---- scenes without BLEND pay nothing ---------------------------------------------------------------
def test_blend_code_is_compiled_only_for_scenes_with_blend(gpu):
    """The feature define is 0 without a BLEND material and every scene-reading pass is compiled
    with it; the scene's report lists it as left out. With one BLEND material it is 1."""
    for alpha_mode, want in (("OPAQUE", 0), ("BLEND", 1)):
        scene = veil_scene(effect=rv.Effect.SHADOWS)
        scene.materials["Veil"].alpha_mode = alpha_mode
        assert ("SCENE_HAS_ALPHA_BLEND" in scene.features) == bool(want)
        with Renderer(scene, rv.graphs.hybrid(preset="raw", gbuffer="rt"), views=view_set(*VEIL_VIEWS)) as r:
            r.render()
            compiled = r.compiled
            seen = {name: p.defines()["SCENE_HAS_ALPHA_BLEND"] for name, p in compiled.passes.items()
                    if hasattr(p, "defines") and "SCENE_HAS_ALPHA_BLEND" in p.defines()}
            assert {"GBuffer", "Direct", "Shadows"} <= set(seen), seen
            assert set(seen.values()) == {want}, seen
            assert r.gpu_scene.defines()["SCENE_HAS_ALPHA_BLEND"] == want
            left_out = r.gpu_scene.report()["left_out"]
            assert (left_out.get("SCENE_HAS_ALPHA_BLEND") == "shader code only") == (not want), left_out
