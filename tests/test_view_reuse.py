"""Shading reused across views (rayvr.passes.TraceDecision, hybrid(reuse='views')): a second eye
or a grid's other views take the shaded light of the same rough surface in a source view, and
trace only what the source cannot show them: disocclusions, glossy lobes, mirrors. On llvmpipe at
32x32 per view: the reused static stereo Cornell box matches independent eyes within the noise,
the pixels a box hides from the first eye are traced by the second, a mirror is traced in every
view, the source eye is untouched, and rays follow the decision."""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError
from rayvr.passes import TraceDecision
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.xr.cameras import stereo_views
from rayvr.xr.views import Fov, Pose

from decision_scenes import DECISION, NONE, REUSE, TRACE, decision_graph, lambert_cornell

SIZE = (32, 32)


def graph(**kw):
    return decision_graph("GBuffer.posW", "GBuffer.effect", **kw)


def kinds(r) -> np.ndarray:
    return r.read_output(DECISION)[..., 0] & 3


def mean_color(scene, frames, views=2, **kw):
    """(mean HDR radiance over `frames` frames (views, h, w, 3), rays per view of the last frame)."""
    with Renderer(scene, graph(**kw), views=views, size=SIZE) as r:
        total = 0.0
        for _ in range(frames):
            r.render()
            total = total + r.read_output("Composite.color")[..., :3].astype(np.float64)
        return total / frames, r.compiled.ray_counts()


def rel_mse(a, b, eps=1e-2):
    return float(np.mean((a - b) ** 2 / (b * b + eps)))


def trimmed_rel_mse(a, b, eps=1e-2, drop=0.02):
    e = np.sort(((a - b) ** 2 / (b * b + eps)).mean(axis=-1).ravel())
    return float(e[:int(len(e) * (1 - drop))].mean())


def test_a_static_stereo_cornell_box_with_reuse_matches_independent_eyes_within_the_noise(gpu):
    scene = lambert_cornell()
    reference, _ = mean_color(scene, 256)               # independent eyes, converged
    independent, rays_independent = mean_color(scene, 16)
    reused, rays_reused = mean_color(scene, 16, reuse="views")
    # the source eye is the same render, ray for ray
    assert np.array_equal(reused[0], independent[0]) and rays_reused[0] == rays_independent[0]
    # the second eye traces little: the column the first eye's frustum misses and a few box edges
    assert rays_reused[1] <= 0.1 * rays_reused[0]
    # ... and is as close to the converged image as an independent second eye (the noise of 16
    # frames of 1 light sample, shared with the first eye instead of its own)
    e_reused, e_independent = rel_mse(reused[1], reference[1]), rel_mse(independent[1], reference[1])
    assert e_reused < 1.5 * e_independent + 1e-4, (e_reused, e_independent)


def box_stereo():
    """Wide-apart eyes over the box on its plane: the box hides a strip of plane from one eye that
    the other sees."""
    eye = Pose([0.0, 1.8, 1.6], [-0.3826834, 0.0, 0.0, 0.9238795])   # 45 degrees down
    fov = Fov.symmetric(50.0, 1.0)
    return stereo_views(eye, 0.5, fov, fov, SIZE)


def seen_by_the_first_eye(views, pos, word):
    """(hidden, shown): the second eye's drawn pixels whose point lands, in the first eye, on another
    surface or on the same one (float64, independent of the GPU; off the image: neither)."""
    vp = views.matrices(views.origin())["view_proj"][0]
    h, w = SIZE[1], SIZE[0]
    clip = np.concatenate([pos[1, ..., :3], np.ones((h, w, 1))], axis=-1) @ vp.T
    w_clip = np.where(clip[..., 3:] > 0, clip[..., 3:], 1.0)   # pixels with nothing drawn are left out below
    px = np.floor((clip[..., :2] / w_clip * 0.5 + 0.5) * [w, h]).astype(int)
    inside = (px[..., 0] >= 0) & (px[..., 0] < w) & (px[..., 1] >= 0) & (px[..., 1] < h)
    qx, qy = np.clip(px[..., 0], 0, w - 1), np.clip(px[..., 1], 0, h - 1)
    drawn = word[1] != 0xFF
    seen_as = word[0][qy, qx]
    gap = np.linalg.norm(pos[0][qy, qx, :3] - pos[1, ..., :3], axis=-1)
    return (drawn & inside & ((seen_as != word[1]) | (gap > 0.05)),
            drawn & inside & (seen_as == word[1]) & (gap < 0.01))


def test_pixels_a_box_hides_from_the_first_eye_are_traced_by_the_second(gpu):
    scene = builtin.box_on_plane()
    for name in ("Plane", "Box"):
        scene.materials[name].effect = rv.Effect.SHADOWS
    views = box_stereo()
    with Renderer(scene, graph(reuse="views"), views=views) as r:
        r.render()
        k = kinds(r)
        assert not (r.read_output(DECISION)[..., 0] & 4).any()   # no SVGF: no pixel is flagged DECISION_SPREAD
        pos = r.read_output("GBuffer.posW").astype(np.float64)
        word = r.read_output("GBuffer.effect")[..., 0]
        rays = r.compiled.ray_counts()
    hidden, shown = seen_by_the_first_eye(views, pos, word)
    assert hidden.sum() >= 20, "the scene must hide some plane from the first eye"
    assert (k[1][hidden] == TRACE).all(), "a disocclusion was filled"
    assert (k[1][shown] == REUSE).mean() > 0.97
    assert (k[0][word[0] != 0xFF] == TRACE).all()   # the source eye traces all
    assert rays[1] >= hidden.sum()                   # one shadow ray each at least


def test_a_mirror_is_traced_in_every_view_and_matches_its_own_render(gpu):
    scene = builtin.mirror_and_checker()
    for name in ("CheckerWhite", "CheckerBlack"):
        scene.materials[name].effect = rv.Effect.SHADOWS
    eye = Pose([0.0, 0.0, 1.0])
    fov = Fov.symmetric(60.0, 1.0)
    views = stereo_views(eye, 0.064, fov, fov, SIZE)
    out = {}
    for reuse in (None, "views"):
        with Renderer(scene, graph(reuse=reuse), views=views) as r:
            r.render()
            out[reuse] = (r.read_output("Composite.color")[..., :3], r.read_output("GBuffer.effect")[..., 0],
                          kinds(r) if reuse else None)
    color, word, k = out["views"]
    mirror = (word[1] & 0xFF) == int(rv.Effect.REFLECTIONS)
    assert mirror.sum() > 100
    assert (k[1][mirror] == TRACE).all()
    assert np.array_equal(color[1][mirror], out[None][0][1][mirror])   # traced as an independent eye does


@pytest.mark.parametrize("effect", [rv.Effect.SHADOWS, rv.Effect.REFLECTIONS])
def test_a_smooth_dielectric_without_traced_reflections_may_reuse_its_light(gpu, effect):
    """A smooth plastic plane (roughness 0: a delta specular layer over a white base) under a point
    light. A SHADOWS pixel's light samples give its delta lobe nothing, so its direct light is the
    base's alone, the same from either eye: with `reuse_delta_lobes` the second eye reuses it and
    renders what it renders alone. A REFLECTIONS pixel traces its mirror: never reused."""
    scene = builtin.box_on_plane()
    plane = scene.materials["Plane"]
    plane.effect, plane.metallic, plane.roughness, plane.specular = effect, 0.0, 0.0, 1.0
    scene.materials["Box"].effect = rv.Effect.SHADOWS
    views = box_stereo()
    out = {}
    for delta in (False, True, None):
        g = graph(reuse="views" if delta is not None else None)
        if delta is not None:
            g.update_pass("Decision", {"reuse_delta_lobes": delta})
        with Renderer(scene, g, views=views) as r:
            r.render()
            out[delta] = (kinds(r) if delta is not None else None, r.read_output("Composite.color")[1, ..., :3])
            pos = r.read_output("GBuffer.posW").astype(np.float64)
            word = r.read_output("GBuffer.effect")[..., 0]
    _, shown = seen_by_the_first_eye(views, pos, word)
    on_plane = shown[...] & (word[1] != 0xFF) & (pos[1, ..., 1] + views.origin()[1] < 0.01)
    assert on_plane.sum() > 100
    assert (out[False][0][1][on_plane] != REUSE).all(), "a delta lobe was reused without reuse_delta_lobes"
    reused = out[True][0][1][on_plane] == REUSE
    if effect == rv.Effect.REFLECTIONS:
        assert not reused.any(), "a traced mirror was reused"
        return
    assert reused.mean() > 0.9
    independent, mine = out[None][1][on_plane].astype(np.float64), out[True][1][on_plane].astype(np.float64)
    assert abs(mine.mean() - independent.mean()) < 0.02 * independent.mean()


def test_a_glossy_surface_is_reused_where_its_lobe_is_wide_against_the_eyes_parallax(gpu):
    scene = builtin.box_on_plane()
    plane = scene.materials["Plane"]
    plane.effect, plane.metallic, plane.roughness = rv.Effect.SHADOWS, 1.0, 0.45   # below reuse_min_roughness
    scene.materials["Box"].effect = rv.Effect.SHADOWS
    views = box_stereo()
    alpha = 0.45 ** 2
    out = {}
    for fraction in (0.0, 1.0):
        g = graph(reuse="views")
        g.update_pass("Decision", {"reuse_lobe_fraction": fraction})
        with Renderer(scene, g, views=views) as r:
            r.render()
            out[fraction] = kinds(r)
            pos = r.read_output("GBuffer.posW").astype(np.float64)
            word = r.read_output("GBuffer.effect")[..., 0]
    _, shown = seen_by_the_first_eye(views, pos, word)
    pos = pos[1, ..., :3]
    origin = views.origin()
    eyes = np.array([v.pose.position for v in views.views], np.float64) - origin   # render space, as posW
    a, b = eyes[1] - pos, eyes[0] - pos
    parallax = np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), (a * b).sum(-1))   # float64, per pixel
    on_plane = (word[1] != 0xFF) & (pos[..., 1] + origin[1] < 0.01)
    reused_1 = out[1.0][1] == REUSE
    assert (out[0.0][1][on_plane] == TRACE).all(), "roughness 0.45 < 0.5: traced by roughness alone"
    near, far = on_plane & (parallax > 1.05 * alpha), on_plane & shown & (parallax < 0.95 * alpha)
    assert near.sum() > 20 and far.sum() > 20, "the plane must span both sides of the threshold"
    assert not reused_1[near].any(), "a lobe narrower than the parallax was reused"
    assert reused_1[far].mean() > 0.9


@pytest.mark.parametrize("stride", [2, TraceDecision.PROPERTIES["source_stride"]])
def test_a_camera_grid_reuses_from_its_sources(gpu, stride):
    """16 views in a 4x4 grid: sources every `stride`-th row and column (2: four of them; the
    default 4: the corner view alone) trace, the others reuse most of their pixels (at 16x16 the
    view three steps from its source on both axes still reuses 78%, tracing 0.31x its rays)."""
    scene = lambert_cornell()
    with Renderer(scene, graph(reuse="views", decision={"source_stride": stride}), views=16, size=(16, 16)) as r:
        r.render()
        rays = r.compiled.ray_counts()
        k = kinds(r)
    cols = rv.xr.grid_for_views(16)[0]
    sources = [v for v in range(16) if (v % cols) % stride == 0 and (v // cols) % stride == 0]
    assert len(sources) == math.ceil(cols / stride) * math.ceil(16 // cols / stride)
    reused = []
    for v in range(16):
        drawn = k[v] != NONE
        if v in sources:
            assert (k[v][drawn] == TRACE).all()
        else:
            reused.append((k[v][drawn] == REUSE).mean())
            assert reused[-1] > 0.75 and rays[v] < 0.4 * rays[0], (v, reused[-1], rays[v], rays[0])
    assert np.mean(reused) > 0.85


def test_the_path_traced_graphs_primary_hits_are_reused(gpu):
    scene = builtin.cornell_box()
    means, rays = {}, {}
    for reuse, frames in ((None, 64), (None, 8), ("views", 8)):
        g = rv.graphs.path_traced(reuse=reuse, max_bounces=2)
        with Renderer(scene, g, views=2, size=SIZE) as r:
            for _ in range(frames):
                r.render()
            means[reuse, frames] = r.read_output("Accumulate.dst")[..., :3].astype(np.float64)
            rays[reuse] = r.compiled.ray_counts()
    assert rays["views"][1] < 0.3 * rays["views"][0]
    assert np.array_equal(means["views", 8][0], means[None, 8][0])     # the source eye traced as before
    # path tracing's noise is heavy-tailed: no bias, and the errors without their largest 2%
    reference, reused, independent = means[None, 64][1], means["views", 8][1], means[None, 8][1]
    assert abs(reused.mean() - reference.mean()) < 0.02 * reference.mean()
    e_reused, e_independent = trimmed_rel_mse(reused, reference), trimmed_rel_mse(independent, reference)
    assert e_reused < 1.5 * e_independent, (e_reused, e_independent)


def test_reuse_is_left_out_with_one_view_and_absent_when_off(gpu):
    scene = lambert_cornell()
    with Renderer(scene, graph(reuse="views"), views=1, size=SIZE) as r:
        assert "Decision" in r.compiled.plan.pruned
        assert "one view" in r.compiled.plan.pruned["Decision"]
        assert DECISION not in r.compiled.plan.resources
    g = rv.graphs.hybrid()
    assert "Decision" not in g.passes


def test_bad_trace_settings_are_one_clear_error(gpu):
    with pytest.raises(OptionError, match="reuse='mirror'.*'views'"):
        rv.graphs.hybrid(reuse="mirror")
    with pytest.raises(OptionError, match="decision=.*reuse='views'"):
        rv.graphs.hybrid(decision={"periphery_share": 0.5})
    with pytest.raises(OptionError, match="TraceDecision.*source_stride"):
        TraceDecision(source_stride=1)
    with pytest.raises(OptionError, match="reuse_min_roughness"):
        TraceDecision(reuse_min_roughness=2.0)
    with pytest.raises(OptionError, match="'spread' follows denoise='svgf'"):
        rv.graphs.hybrid(reuse="views", decision={"spread": True})


def test_reuse_under_the_clean_preset_converges_as_independent_eyes_do(gpu):
    """Probe GI, SVGF and TAA over reused light: a still stereo view's second eye ends as close to
    the converged image as independent eyes do, and so do both eyes when they alternate as the
    source."""
    scene = lambert_cornell()
    out = {}
    for reuse, frames, alternate in ((None, 96, False), (None, 12, False), ("views", 12, False), ("views", 12, True)):
        g = rv.graphs.hybrid(reuse=reuse, decision={"alternate": True} if alternate else None)
        with Renderer(scene, g, views=2, size=SIZE) as r:
            for _ in range(frames):
                r.render()
            out[reuse, frames, alternate] = r.read_output("TAA.dst")[..., :3].astype(np.float64)
    reference = out[None, 96, False]
    e_independent = rel_mse(out[None, 12, False][1], reference[1])
    e_reused = rel_mse(out["views", 12, False][1], reference[1])
    assert e_reused < 1.5 * e_independent + 1e-4, (e_reused, e_independent)
    # eyes that take turns as the source carry their denoiser's history through the frames they borrow
    e_alternate = max(rel_mse(out["views", 12, True][v], reference[v]) for v in range(2))
    assert e_alternate < 1.5 * e_independent + 1e-4, (e_alternate, e_independent)


def test_restir_direct_light_is_reused_across_eyes(gpu):
    """ReSTIR DI under the trace decision: the source eye is the same render, reservoir for
    reservoir; the second eye resamples only where it traces (its spatial reuse skips pixels that
    made no reservoir this frame) and fills the rest, as close to the converged image as an
    independent second eye; with foveation too, and under the clean preset, nothing non-finite."""
    scene = lambert_cornell()
    reference, _ = mean_color(scene, 96, direct="restir")
    independent, rays_independent = mean_color(scene, 8, direct="restir")
    reused, rays_reused = mean_color(scene, 8, direct="restir", reuse="views")
    assert np.array_equal(reused[0], independent[0]) and rays_reused[0] == rays_independent[0]
    assert rays_reused[1] <= 0.1 * rays_reused[0]
    e_reused, e_independent = rel_mse(reused[1], reference[1]), rel_mse(independent[1], reference[1])
    assert e_reused < 1.5 * e_independent + 1e-4, (e_reused, e_independent)
    g = rv.graphs.hybrid(direct="restir", reuse="views", foveation="fixed")
    with Renderer(scene, g, views=2, size=SIZE) as r:
        for _ in range(4):
            r.render()
        shown = r.read_output("TAA.dst")[..., :3]
        assert np.isfinite(shown).all() and not any(r.profile().nonfinite.values())
        assert abs(shown[1].mean() - shown[0].mean()) < 0.05 * shown[0].mean()   # the eyes see one box alike


def test_reused_light_is_denoised_once_in_the_source_eye(gpu):
    """SVGF filters the source eye; the second eye's reused pixels take its filtered light at their
    point (bilinear over the first eye's pixels there), remodulated by their own albedo: on a
    wall of one colour, the first eye's denoised colour there. Filtering each eye's own noisy light
    left them 1-13% apart. The decision flags those pixels for SVGF, and the composite leaves them
    (0 in its colour): no ray pass fills them nor the composite lights them."""
    g = rv.graphs.hybrid(reuse="views")
    for pin in ("SVGF.color", DECISION, "GBuffer.effect", "GBuffer.faceNormalW", "Composite.color"):
        g.mark_output(pin)
    with Renderer(lambert_cornell(), g, views=2, size=SIZE) as r:
        for _ in range(2):
            r.render()
        color = r.read_output("SVGF.color")[..., :3].astype(np.float64)
        t = r.read_output(DECISION)
        word = r.read_output("GBuffer.effect")[..., 0]
        ng = r.read_output("GBuffer.faceNormalW")[..., :3].astype(np.float64)
        composite = r.read_output("Composite.color")[..., :3]
    k = t[..., 0] & 3
    flagged = (t[..., 0] & 4) != 0   # DECISION_SPREAD
    assert flagged[1].sum() > 500 and np.array_equal(flagged, k == REUSE)
    assert (composite[flagged] == 0).all() and (composite[0][word[0] != 0xFF] > 0).any()
    px, py = (t[1, ..., 1] & 0xFFFF) / 8.0 - 0.5, (t[1, ..., 1] >> 16) / 8.0 - 0.5   # taps at pixel centres
    errors = []
    for y, x in zip(*np.nonzero(k[1] == REUSE)):
        x0, y0 = int(np.floor(px[y, x])), int(np.floor(py[y, x]))
        fx, fy = px[y, x] - x0, py[y, x] - y0
        taps = [((y0, x0), (1 - fx) * (1 - fy)), ((y0, x0 + 1), fx * (1 - fy)), ((y0 + 1, x0), (1 - fx) * fy),
                ((y0 + 1, x0 + 1), fx * fy)]
        if not (0 <= x0 < SIZE[0] - 1 and 0 <= y0 < SIZE[1] - 1):
            continue
        if any(k[0][q] != TRACE or word[0][q] != word[1][y, x] or ng[0][q] @ ng[1][y, x] < 0.999 for q, _ in taps):
            continue   # the wall's edge: the taps that show its surface alone
        expected = sum(w * color[0][q] for q, w in taps)
        errors.append(np.abs(color[1][y, x] - expected).max() / expected.max())
    assert len(errors) > 300
    assert max(errors) < 2e-3, np.percentile(errors, [50, 90, 100])


def test_alternating_sources_swap_the_eyes_each_frame(gpu):
    scene = lambert_cornell()
    with Renderer(scene, graph(reuse="views", decision={"alternate": True}), views=2, size=SIZE) as r:
        sourced = []
        for _ in range(2):
            r.render()
            k = kinds(r)
            sourced.append([bool((k[v][k[v] != NONE] == TRACE).all()) for v in range(2)])
            rays = r.compiled.ray_counts()
            assert min(rays) < 0.2 * max(rays)
    assert sourced == [[True, False], [False, True]]


SHARED_LIGHT = 8   # glsl/trace_decision.glsl DECISION_SHARED_LIGHT


def glossy_box_on_plane(effect, roughness=0.2, glass=False):
    scene = builtin.box_on_plane()
    plane = scene.materials["Plane"]
    plane.effect, plane.metallic, plane.roughness = effect, 0.0 if glass else 1.0, roughness
    if glass:   # the builtin plane is Lambertian: no specular layer (specular 0) until given one
        plane.transmission, plane.specular = 1.0, 1.0
    scene.materials["Box"].effect = rv.Effect.SHADOWS
    return scene


@pytest.mark.parametrize("effect, glass", [(rv.Effect.SHADOWS, False), (rv.Effect.REFLECTIONS, False),
                                           (rv.Effect.SHADOWS, True)], ids=["shadows", "reflections", "glass"])
def test_a_glossy_surface_shades_its_own_lobe_over_the_source_eyes_light_sample(gpu, effect, glass):
    """A metal plane of roughness 0.2 under one point light, seen by wide-apart eyes: its lobe is
    narrower than their parallax, so the second eye cannot take the first's shaded light; it shades
    its own lobe towards the first eye's light sample over that sample's shadow ray. With one point
    light that is its own independent render exactly, but for shadow edges, with no shadow ray of
    its own (REFLECTIONS: its reflection rays are its own, so it traces those). A glass plane
    (transmission 1), whose shaded light is never reused, shares its light samples the same way."""
    scene = glossy_box_on_plane(effect, glass=glass)
    views = box_stereo()
    out = {}
    for name, reuse, decision in (("independent", None, None), ("traced", "views", {"share_light_samples": False}),
                                  ("shared", "views", None), ("shaded", "views", {"reuse_min_roughness": 0.0})):
        g = graph(reuse=reuse, decision=decision)
        g.mark_output("Shadows.shadowed")
        with Renderer(scene, g, views=views) as r:
            r.render()
            out[name] = (r.read_output("Shadows.shadowed")[..., :3].astype(np.float64), r.compiled.ray_counts(),
                         r.read_output(DECISION)[..., 0] if reuse else None)
    independent, shared = out["independent"][0], out["shared"][0]
    t = out["shared"][2][1]
    flagged = (t & SHARED_LIGHT) != 0
    assert flagged.sum() > 300 and ((t[flagged] & 3) == TRACE).all()
    assert not (out["traced"][2][1] & SHARED_LIGHT).any()
    assert np.array_equal(shared[0], independent[0])   # recording its samples leaves the source eye as it was
    own = ((t & 3) == TRACE) & ~flagged
    rays_saved = out["traced"][1][1] - out["shared"][1][1]
    assert 0.9 * flagged.sum() <= rays_saved <= flagged.sum()   # one shadow ray each
    if effect == rv.Effect.SHADOWS:
        assert out["shared"][1][1] <= own.sum()
    err = np.abs(shared[1] - independent[1]).max(-1)[flagged]
    assert (err <= 2e-3 * (1.0 + independent[1].max(-1)[flagged])).mean() > 0.98, np.sort(err)[-10:]
    if glass:   # never reused, at any roughness: what the eyes see through it differs
        assert not ((out["shaded"][2][1] & 3) == REUSE)[flagged].any()
        return
    # the first eye's shaded light would put its highlight where the first eye sees it
    shaded = np.abs(out["shaded"][0][1] - independent[1]).max(-1)[flagged]
    assert shaded.max() > 0.05 and shaded.mean() > 20 * err.mean()


@pytest.mark.parametrize("effect, glass", [(rv.Effect.SHADOWS, False), (rv.Effect.REFLECTIONS, False),
                                           (rv.Effect.SHADOWS, True)], ids=["shadows", "reflections", "glass"])
def test_a_shared_area_light_sample_converges_to_the_same_image(gpu, effect, glass):
    """Under the Cornell box's area light (an emissive quad: its samples' pdf per unit area), glossy
    walls and boxes whose second-eye pixels take the first eye's light samples converge to the
    independent eyes' image, and are as close to it after 16 frames as an independent second eye
    (REFLECTIONS: the light sample's MIS weight against the pixel's own reflection rays is its own;
    glass: the tall box is glass, whose pixels share too)."""
    scene = lambert_cornell()
    for name in ("Floor", "BackWall", "TallBox", "ShortBox"):
        m = scene.materials[name]
        m.metallic, m.roughness, m.effect = 0.5, 0.2, effect
    if glass:
        m = scene.materials["TallBox"]
        m.metallic, m.transmission, m.specular = 0.0, 1.0, 1.0
    reference, _ = mean_color(scene, 512)
    independent, _ = mean_color(scene, 16)
    with Renderer(scene, graph(reuse="views"), views=2, size=SIZE) as r:
        total = 0.0
        for frame in range(256):
            r.render()
            total = total + r.read_output("Composite.color")[..., :3].astype(np.float64)
            if frame == 15:
                shared = total / 16
        flagged = (r.read_output(DECISION)[1, ..., 0] & SHARED_LIGHT) != 0
        on_tall_box = (r.read_output("GBuffer.effect")[1, ..., 0] >> 8) == scene.materials.index("TallBox")
        rays = r.compiled.ray_counts()
    assert flagged.sum() > 200 and rays[1] < (0.5 if effect == rv.Effect.SHADOWS else 0.9) * rays[0]
    assert (flagged & on_tall_box).sum() > 20   # glass or not, the tall box shares
    ref = reference[1][flagged]
    converged = (total / 256)[1][flagged]
    assert abs(converged.mean() - ref.mean()) < 0.02 * ref.mean(), (converged.mean(), ref.mean())
    e_shared, e_independent = rel_mse(shared[1][flagged], ref), rel_mse(independent[1][flagged], ref)
    assert e_shared < 1.5 * e_independent + 1e-4, (e_shared, e_independent)


def test_only_reuse_compiles_the_spread_and_the_shared_light_samples(gpu):
    """The decision flags pixels for SVGF to spread to, and shares light samples, only when views
    reuse: with foveation alone SVGF compiles no spread stage, the composite reads no decision and
    RTShadows records no samples (no `sharedLights` texture)."""
    for reuse in (None, "views"):
        g = rv.graphs.hybrid(foveation="fixed", reuse=reuse)
        with Renderer(lambert_cornell(), g, views=2, size=SIZE) as r:
            r.render()
            report = r.report()
        on = reuse is not None
        assert ("SVGF_SHARED" in report.defines["SVGF"]) == on
        assert (report.defines["Shadows"].get("SHARED_LIGHT") == 1) == on
        assert ("TRACE_DECISION" in report.defines["Composite"]) == on
        assert any(res.name == "Shadows.sharedLights" for res in report.resources) == on


def test_workgroups_over_reused_views_and_render_the_same_image(gpu):
    """With 16 views (sources every 2nd column and row of a 4x4 grid: four) the ray passes and the
    composite take one view per workgroup (`one_view_tiles`), in both of RTShadows' dispatches (the
    glossy boxes' pixels take their source's light sample) and RTReflections'. Without it the
    composite, whose workgroups span four views, takes the four sources first, then the others in
    grid order (`source_views_first`). One view per workgroup, the composite and RTReflections run
    over the decision's work tiles (`work_tiles`, the default), or over every tile without; RTShadows' workgroups
    may gather the pixels of 8 tiles side by side (`compact_tiles`; 16 of its 4x2 tiles: more tiles
    than lanes). Which lane shades which pixel, and which workgroups launch, change nothing: the
    images and rays per view are those of the grid order's workgroups over several views."""
    scene = lambert_cornell()
    for name in ("TallBox", "ShortBox"):
        m = scene.materials[name]
        m.metallic, m.roughness = 0.5, 0.2
    scene.materials["TallBox"].effect = rv.Effect.REFLECTIONS
    stride = 2
    configs = {"grid": {"source_views_first": False, "one_view_tiles": False},
               "sources first": {"one_view_tiles": False}, "one view": {}, "every tile": {"work_tiles": False},
               "gathered": {}, "narrow": {}}
    out = {}
    for name, props in configs.items():
        g = rv.graphs.hybrid(reuse="views", gi="probes", denoise="svgf")
        g.update_pass("Decision", {**props, "source_stride": stride})
        if name == "gathered":
            g.update_pass("Shadows", {"compact_tiles": 8})
        if name == "narrow":   # more tiles than lanes
            g.update_pass("Shadows", {"tile": [4, 2], "compact_tiles": 16})
        g.mark_output("SVGF.color")
        g.mark_output(DECISION)
        with Renderer(scene, g, views=16, size=(16, 16)) as r:
            for _ in range(2):
                r.render()
            out[name] = (r.read_output("Composite.color"), r.read_output("SVGF.color"), r.compiled.ray_counts(),
                         {p: r.compiled.passes[p].defines() for p in ("Shadows", "Composite", "Reflections")},
                         r.read_output(DECISION)[..., 0])
    cols = rv.xr.grid_for_views(16)[0]
    sources = [v for v in range(16) if (v % cols) % stride == 0 and (v // cols) % stride == 0]
    composite = out["sources first"][3]["Composite"]
    assert composite["RAY_GROUP_Z"] == 4 and "RAY_GROUP_VIEW_ORDER" not in out["grid"][3]["Composite"]
    order = [int(v.strip(" u")) for v in composite["RAY_GROUP_VIEW_ORDER"].split("(")[1].rstrip(")").split(",")]
    assert order == sources + [v for v in range(16) if v not in sources]
    for p in ("Shadows", "Composite", "Reflections"):
        assert out["one view"][3][p]["RAY_GROUP_Z"] == 1 and out["grid"][3][p]["RAY_GROUP_Z"] > 1, p
        assert out["one view"][3][p].get("WORK_TILES_INPUT") == 1, p
        assert "WORK_TILES_INPUT" not in out["every tile"][3][p] and "WORK_TILES_INPUT" not in out["grid"][3][p], p
    for name in configs:
        want = {"gathered": 8, "narrow": 16}.get(name)   # view reuse alone: none by default
        assert out[name][3]["Shadows"].get("RAY_PASS_COMPACT") == want, name
    assert "WORK_TILES_INPUT" not in out["gathered"][3]["Shadows"]   # the gather takes the tiles' place
    assert ((out["one view"][4] & SHARED_LIGHT) != 0).sum() > 50   # RTShadows' second dispatch has pixels
    for name in ("sources first", "one view", "every tile", "gathered", "narrow"):
        np.testing.assert_array_equal(out[name][0], out["grid"][0])
        np.testing.assert_array_equal(out[name][1], out["grid"][1])
        assert out[name][2] == out["grid"][2]
    assert all(out["grid"][2][v] > 0 for v in sources)


@pytest.mark.parametrize("views", [2, 16])
def test_the_work_tiles_are_the_tiles_with_a_pixel_whose_light_is_not_spread(gpu, views):
    """The decision lists, once each, every 8x4 tile of a view that holds a pixel whose light is its
    own (not flagged DECISION_SPREAD, the sky included, and the tiles past the image's edge that
    hold such a pixel) and no other: in the reusing views most tiles are left out."""
    from rayvr.passes.compaction import read_pixel_list
    size = (32, 30)   # the last row of tiles half outside
    g = rv.graphs.hybrid(reuse="views")
    g.update_pass("Decision", {"source_stride": 2, "work_tiles": True})
    g.mark_output(DECISION)
    g.mark_output("Decision.workTiles")
    with Renderer(lambert_cornell(), g, views=views, size=size) as r:
        r.render()
        own = (r.read_output(DECISION)[..., 0] & 4) == 0   # not DECISION_SPREAD
        n, tiles = read_pixel_list(r.compiled.get_output("Decision.workTiles"))
    rows = -(-size[1] // 4)
    padded = np.zeros((views, rows * 4, size[0]), bool)
    padded[:, :size[1]] = own
    want = padded.reshape(views, rows, 4, size[0] // 8, 8).any(axis=(2, 4))   # (view, tile y, tile x)
    listed = np.zeros_like(want)
    listed[tiles[:, 2], tiles[:, 1], tiles[:, 0]] = True
    assert n == len(np.unique(tiles, axis=0))   # each tile once
    np.testing.assert_array_equal(listed, want)
    assert want[0].all() and want[1:].mean() < 0.8   # the source view whole, the others far from it


@pytest.mark.parametrize("foveation, denoise, fills", [("none", "svgf", False), ("fixed", "svgf", True),
                                                       ("none", None, True)])
def test_the_ray_passes_fill_only_where_the_decision_leaves_them_pixels(gpu, foveation, denoise, fills):
    """With SVGF spreading every reused pixel and no foveation, no pixel is left to the ray passes'
    fills: they are left out, and the compile report says so. Foveation (a pixel takes a traced
    neighbour's light in its own view) or no denoiser (reused light is filled) keeps them."""
    g = rv.graphs.hybrid(foveation=foveation, reuse="views", denoise=denoise)
    with Renderer(lambert_cornell(), g, views=2, size=SIZE) as r:
        r.render()
        shadows = r.compiled.passes["Shadows"]
        report = r.report()
        image = r.read_output("ToneMap.dst")
    assert (shadows._fill._res is not None) == fills
    assert ("decision_fill" not in report.defines["Shadows"]) == fills
    assert image[..., :3].max() > 0


def test_under_foveation_rtshadows_gathers_its_dithered_pixels_and_renders_the_same_image(gpu):
    """Foveation's dither leaves a few traced pixels in every tile of the periphery: RTShadows'
    workgroups then gather those of 8 tiles (`compact_tiles` 0, the default), without it (reuse
    alone) not; gathered or not, the same image and the same rays."""
    out = {}
    for name, tiles in (("auto", 0), ("own tile", 1)):
        g = rv.graphs.hybrid(foveation="fixed")
        g.update_pass("Decision", {"foveal_radius_deg": 2.0})
        g.update_pass("Shadows", {"compact_tiles": tiles})
        with Renderer(lambert_cornell(), g, views=2, size=(40, 24)) as r:
            r.render()
            out[name] = (r.read_output("Composite.color"), r.compiled.ray_counts(),
                         r.compiled.passes["Shadows"].defines().get("RAY_PASS_COMPACT"))
    assert out["auto"][2] == 8 and out["own tile"][2] is None
    np.testing.assert_array_equal(out["auto"][0], out["own tile"][0])
    assert out["auto"][1] == out["own tile"][1] and 0 < sum(out["auto"][1]) < 2 * 40 * 24


@pytest.mark.parametrize("value", [33, -1, 2.5])
def test_compact_tiles_outside_0_to_32_is_refused_naming_the_pass(value):
    with pytest.raises(rv.OptionError, match=r"pass RTShadows: property 'compact_tiles' must be an integer from 0 to 32"):
        rv.passes.RTShadows(compact_tiles=value)


def test_over_the_list_each_of_rtshadows_dispatches_takes_its_own_pixels(gpu):
    """RTShadows over the compaction's list (`dispatch_mode` 'list') under view reuse: the list holds
    every traced pixel, and each of the two dispatches keeps those it shades (ray_pass_accepts: its
    own light sample, or the source's); the same image and rays as over the image."""
    scene = glossy_box_on_plane(rv.Effect.SHADOWS)
    out = {}
    for mode in ("image", "list"):
        g = graph(reuse="views")
        g.update_pass("Shadows", {"dispatch_mode": mode})
        g.mark_output("Shadows.shadowed")
        with Renderer(scene, g, views=box_stereo()) as r:
            r.render()
            out[mode] = (r.read_output("Shadows.shadowed"), r.compiled.ray_counts(),
                         r.read_output(DECISION)[1, ..., 0])
    assert ((out["list"][2] & SHARED_LIGHT) != 0).sum() > 300   # the second dispatch has pixels
    np.testing.assert_array_equal(out["list"][0], out["image"][0])
    assert out["list"][1] == out["image"][1]
