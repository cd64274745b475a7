"""Glass in the hybrid: what lies behind a transmissive surface shows through it (RTReflections'
transmission bounces), and the passes that shade the G-buffer surface know the material transmits
(no diffuse light for a surface whose light passes through it)."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.builtin import box, lambert, quad_mesh
from rayvr.scene.model import Environment, Material, Scene
from rayvr.xr.cameras import look_at
from rayvr.xr.views import Fov, View, ViewSet

SIZE = 24
WALL = 2.0   # the emissive wall's radiance


def glass(name="Glass", roughness=0.0, effect=rv.Effect.REFLECTIONS) -> Material:
    """White thin-walled glass (glTF ior 1.5: F = 0.04 at normal incidence)."""
    return Material(name, base_color=(1.0, 1.0, 1.0, 1.0), metallic=0.0, roughness=roughness, transmission=1.0,
                    effect=effect)


def glass_box_scene() -> Scene:
    """A closed glass box (thin-walled) before an emissive black wall of radiance WALL, black sky."""
    s = Scene("glass_box")
    s.add_material(glass())
    s.add_material(lambert("Wall", (0.0, 0.0, 0.0), emissive=(1.0, 1.0, 1.0), emissive_strength=WALL))
    s.add_object("Glass", *box((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)), "Glass")
    s.add_object("Wall", *quad_mesh([[-4, -4, -2], [4, -4, -2], [4, 4, -2], [-4, 4, -2]], (0, 0, 1)), "Wall")
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    return s


def centre(img, half=4):
    c = SIZE // 2
    return img[c - half:c + half, c - half:c + half]


@pytest.mark.parametrize("bounces", [1, 0])
def test_a_glass_box_shows_the_wall_behind_it(gpu, bounces):
    """Seen face-on through both of its walls, the box passes (1 - F)^2 = 0.9216 of the wall's
    radiance (F = 0.04 at each wall; inter-reflections add 0.2%): RTReflections' transmission
    bounce carries the path through the far wall. Without it the path ends on the far wall, which
    emits nothing and is lit by nothing: black."""
    views = ViewSet([View(look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0)), Fov.symmetric(20.0, 1.0), SIZE, SIZE,
                          0.01, 100.0)])
    g = rv.graphs.hybrid(preset="raw")
    g.update_pass("Reflections", {"transmission_bounces": bounces})
    frames = 32
    with Renderer(glass_box_scene(), g, views=views) as r:
        mean = 0.0
        for _ in range(frames):
            r.render()
            img = r.read_output("Composite.color")[0, ..., :3].astype(np.float64)
            assert np.isfinite(img).all() and (img >= 0).all()
            mean = mean + img / frames
    seen = centre(mean).mean()
    if bounces:
        # each frame a pixel transmits at both walls (weight 1) or reflects the black sky: 1024
        # such draws per frame's window, 32 frames; 5% is over 6 standard errors
        assert seen == pytest.approx(0.9216 * WALL, rel=0.05)
    else:
        assert seen < 0.05 * WALL


def test_untraced_glass_shows_what_is_behind_it_through_the_probes(gpu):
    """A rough glass quad (effect SHADOWS, its transmission not traced) in the Cornell box, with
    probe GI: where it stands the image shows about what lies behind it (the lit back wall, as
    the probes see it: blurred, times the glass's transmitted albedo ~0.9, + its reflection), not
    the near black of a surface whose transmitted light comes from nowhere (before the probes'
    lookup behind the glass)."""
    def pane_pixels(material: Material | None) -> float:
        scene = builtin.cornell_box()
        if material is not None:
            scene.add_material(material)
            scene.add_object("Pane", *quad_mesh([[-0.12, 0.15, 0.0], [0.12, 0.15, 0.0], [0.12, 0.39, 0.0],
                                                 [-0.12, 0.39, 0.0]], (0, 0, 1)), material.name)
        g = rv.graphs.hybrid(preset="raw", gi="probes", probes={"counts": [4, 4, 4]})
        views = rv.xr.cameras.default_views(scene, 1, (32, 32))
        with Renderer(scene, g, views=views) as r:
            total = 0.0
            for frame in range(16):
                r.render()
                img = r.read_output("Composite.color")[0, ..., :3].astype(np.float64)
                assert np.isfinite(img).all()
                total += img[12:20, 13:19].mean() if frame >= 8 else 0.0   # the pane's middle
        return total / 8

    behind = pane_pixels(None)
    pane = pane_pixels(glass("Pane", roughness=0.5, effect=rv.Effect.SHADOWS))
    assert 0.6 * behind < pane < 1.2 * behind, (pane, behind)
