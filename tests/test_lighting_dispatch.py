"""RTShadows / RTReflections work either on the compaction's pixel list (indirect dispatch) or on
the whole image in 8x8 tiles, where the pixels whose effect needs no such rays leave at once. Both
must light the very same pixels the very same way (the random numbers are seeded per pixel)."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Light
from rayvr.xr.cameras import default_views

OUTPUTS = ("Shadows.shadowed", "Reflections.reflection", "Composite.color")


def scene_with_every_light_kind():
    s = builtin.cornell_box()
    s.lights += [Light("directional", direction=(0.3, -1.0, -0.4), intensity=2.0),
                 Light("point", position=(0.0, 1.0, 0.5), intensity=0.5),
                 Light("spot", position=(0.2, 1.5, 0.2), direction=(0.0, -1.0, 0.0), intensity=3.0,
                       outer_cone_angle=0.5, inner_cone_angle=0.3)]
    for m in s.materials:
        m.effect = rv.Effect.SHADOWS
    s.materials["BackWall"].effect = rv.Effect.RASTER
    floor, box = s.materials["Floor"], s.materials["TallBox"]
    floor.effect = box.effect = rv.Effect.REFLECTIONS
    floor.metallic, floor.roughness = 1.0, 0.0          # mirror
    box.metallic, box.roughness = 1.0, 0.35            # glossy
    return s


def render(gpu, scene, monkeypatch, pixels_2d, max_bounces, tile=(8, 4), views=2):
    g = rv.graphs.hybrid(preset="raw", light_samples=2, max_bounces=max_bounces)
    for name in ("Shadows", "Reflections"):
        g.update_pass(name, {"dispatch_mode": "image" if pixels_2d else "list", "tile": list(tile)})
    for name in (*OUTPUTS[:2], "GBuffer.effect"):
        g.mark_output(name)
    view_set = default_views(scene, views, (40, 36))   # not a multiple of the tiles (nor views of 4)
    with Renderer(scene, g, views=view_set, gpu=gpu) as r:
        r.render()
        for name in ("Shadows", "Reflections"):
            assert r.compiled.passes[name].defines()["PIXELS_2D"] == int(pixels_2d)
        return {name: r.read_output(name).copy() for name in (*OUTPUTS, "GBuffer.effect")}


@pytest.mark.parametrize("max_bounces,tile,views", [(1, (8, 4), 2), (2, (8, 4), 2), (1, (16, 8), 2), (1, (8, 4), 6)])
def test_whole_image_dispatch_lights_the_same_pixels_as_the_list(gpu, monkeypatch, max_bounces, tile, views):
    scene = scene_with_every_light_kind()
    listed = render(gpu, scene, monkeypatch, False, max_bounces, views=views)
    tiled = render(gpu, scene, monkeypatch, True, max_bounces, tile, views)
    effect = listed["GBuffer.effect"][..., 0] & 0xFF   # gbuffer.glsl: the effect id in the low byte
    np.testing.assert_array_equal(effect, tiled["GBuffer.effect"][..., 0] & 0xFF)
    drawn = effect != 0xFF
    # a ray pass writes only the pixels whose effect needs its rays (elsewhere its output is
    # undefined: fresh GPU memory); the composite writes every pixel
    served = {"Shadows.shadowed": drawn & (effect >= int(rv.Effect.SHADOWS)),
              "Reflections.reflection": drawn & (effect >= int(rv.Effect.REFLECTIONS)),
              "Composite.color": np.ones_like(drawn)}
    # enough lit pixels for the comparison to mean something (the sun is shut out of the box: the
    # pixels whose two light samples both chose it are black)
    for name, lit in zip(OUTPUTS, (0.2, 0.02, 0.3)):
        a, b = listed[name][served[name]], tiled[name][served[name]]
        assert np.isfinite(a).all()
        assert (a[..., :3].max(axis=-1) > 0).mean() > lit, f"{name}: too few lit pixels to compare"
        # Same pixels, same random numbers: equal up to the float rounding in which two compiled
        # variants of a shader may differ (bit-identical on llvmpipe; NVIDIA contracts differently,
        # and a second glossy bounce can turn a rounding into another path on a rare pixel).
        lit_a, lit_b = a[..., :3].max(axis=-1) > 0, b[..., :3].max(axis=-1) > 0
        assert (lit_a == lit_b).mean() > 0.999, f"{name}: the two dispatches lit different pixels"
        close = np.isclose(a, b, rtol=1e-3, atol=1e-5).all(axis=-1)
        assert close.mean() > 0.999, f"{name}: {int((~close).sum())} pixels differ beyond rounding"


@pytest.mark.parametrize("path_traced", [False, True])
@pytest.mark.parametrize("reuse", [None, "views"])
def test_ray_passes_run_on_the_image_unless_a_material_is_path_traced(gpu, path_traced, reuse):
    """With a trace decision too (view reuse over two views): its tiles skip the pixels it does not
    trace, which measured faster than the list of the others."""
    scene = scene_with_every_light_kind()
    if path_traced:
        scene.materials["ShortBox"].effect = rv.Effect.PATH_TRACED
    views = default_views(scene, 2 if reuse else 1, (8, 8))
    with Renderer(scene, rv.graphs.hybrid(preset="raw", reuse=reuse), views=views, gpu=gpu) as r:
        assert r.compiled.passes["Reflections"].defines()["PIXELS_2D"] == int(not path_traced)
        assert r.compiled.passes["Shadows"].defines()["PIXELS_2D"] == int(not path_traced)
        # the pixel lists are made only when a pass reads them; the report says why not
        assert ("Compaction" in r.compiled.plan.order) == path_traced
        assert ("leave unused: Shadows.pixels (runs over the whole image" in str(r.report())) == (not path_traced)
        assert ("PIXEL_LIST_INPUT" in r.compiled.passes["Shadows"].defines()) == path_traced


def test_under_view_reuse_the_image_and_the_list_light_the_same_pixels(gpu):
    """With view reuse (reused pixels filled, glossy ones taking the first eye's light samples in a
    second dispatch) the two dispatch forms give the same image."""
    scene = scene_with_every_light_kind()
    out = {}
    for mode in ("list", "image"):
        g = rv.graphs.hybrid(preset="raw", reuse="views")
        for name in ("Shadows", "Reflections"):
            g.update_pass(name, {"dispatch_mode": mode})
        g.mark_output("Decision.decision")
        with Renderer(scene, g, views=default_views(scene, 2, (40, 36)), gpu=gpu) as r:
            r.render()
            out[mode] = (r.read_output("Composite.color")[..., :3].copy(), r.compiled.ray_counts(),
                         r.read_output("Decision.decision")[..., 0])
    t = out["list"][2][1]
    assert ((t & 3) >= 2).sum() > 200 and (t & 8).sum() > 0   # reused, and sharing light samples
    assert out["list"][1] == out["image"][1]
    close = np.isclose(out["list"][0], out["image"][0], rtol=1e-3, atol=1e-5).all(axis=-1)
    assert close.mean() > 0.999, int((~close).sum())
