"""Light selection by power and the environment light, against closed forms and float64 sums:
the alias table's probabilities, 10,000 point lights over a plane, a Lambert plane under a
uniform environment in every pass that lights it, and the environment's bad input."""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.cli.main import main
from rayvr.errors import OptionError, SceneError
from rayvr.scene.builtin import lambert, quad_mesh
from rayvr.scene.environment import load_environment
from rayvr.scene.light_table import (KIND_ENVIRONMENT, KIND_EMISSIVE, KIND_PUNCTUAL, alias_probabilities,
                                     alias_table, build_light_table)
from rayvr.scene.model import Environment, Light, Scene
from rayvr.xr.cameras import look_at
from rayvr.xr.views import Fov, View, ViewSet

SIZE = 24


def test_alias_table_draws_each_entry_by_its_share_of_the_power():
    rng = np.random.default_rng(3)
    for n in (1, 2, 7, 10_000):
        w = rng.exponential(size=n) * (rng.random(n) > 0.2)
        w[0] = max(w[0], 0.5)                          # not all zero
        p = alias_probabilities(*alias_table(w))
        assert p.sum() == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(p, w / w.sum(), rtol=1e-9, atol=1e-15)


def test_light_table_sums_to_one_and_leaves_out_dark_lights():
    t = build_light_table(np.array([4.0, 0.0, 1.0]), np.array([2.0, 2.0]), 1.0)
    assert t.count == 5                                # the dark punctual light is left out
    assert t.probabilities.sum() == pytest.approx(1.0)
    assert t.probability_of(KIND_PUNCTUAL) == pytest.approx(0.5)
    assert t.probability_of(KIND_EMISSIVE) == pytest.approx(0.4)
    assert t.probability_of(KIND_ENVIRONMENT) == pytest.approx(0.1)
    np.testing.assert_allclose(alias_probabilities(t.threshold, t.alias), t.probabilities, rtol=1e-12)
    # each punctual entry carries the punctual lights' share (lights.glsl's local selection), others 0
    share = t.packed()[2::2, 2]
    np.testing.assert_allclose(share, np.where(t.kinds == KIND_PUNCTUAL, 0.5, 0.0), rtol=1e-6)


def plane_scene(albedo=0.5) -> Scene:
    s = Scene("plane")
    s.add_material(lambert("White", (albedo,) * 3))
    s.add_object("Plane", *quad_mesh([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], facing=(0, 1, 0)), "White")
    return s


def down_view(height=3.0) -> ViewSet:
    """A camera above the plane looking straight down at its centre (up: -z)."""
    return ViewSet([View(look_at((0.0, height, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0)),
                         Fov.symmetric(40.0, 1.0), SIZE, SIZE, 0.01, 10.0)])


def plane_points(views) -> np.ndarray:
    """(SIZE, SIZE, 3) where each pixel centre's primary ray meets the plane y = 0 (rows bottom-up)."""
    pts = np.zeros((SIZE, SIZE, 3))
    for j in range(SIZE):
        for i in range(SIZE):
            o, d = views[0].primary_ray((i + 0.5, j + 0.5))
            pts[j, i] = o + d * (-o[1] / d[1])
    return pts


def mean_image(scene, graph, views, pin, frames) -> np.ndarray:
    with rv.Renderer(scene, graph, views=views) as r:
        total = 0.0
        for _ in range(frames):
            r.render()
            total = total + r.read_output(pin)[0, ..., :3].astype(np.float64)
    return total / frames


def test_ten_thousand_point_lights_match_the_float64_sum(gpu):
    """Radiance of a white Lambert plane (rho / pi sum_k I_k cos_k / d_k^2) under 10,000 point
    lights of random intensities, one light sample per pixel and frame drawn by power: the image
    mean over 48 frames within 3% of the float64 sum (the estimator's noise there is ~1%)."""
    rng = np.random.default_rng(7)
    scene = plane_scene(albedo=1.0)
    n = 10_000
    pos = np.column_stack([rng.uniform(-2, 2, n), rng.uniform(0.3, 1.5, n), rng.uniform(-2, 2, n)])
    intensity = rng.exponential(0.002, n)
    scene.lights = [Light("point", position=p, intensity=float(i)) for p, i in zip(pos, intensity)]
    views = down_view()
    pts = plane_points(views)
    d = pos[None, None] - pts[:, :, None]                                  # (S, S, n, 3)
    dist2 = (d ** 2).sum(-1)
    cos = d[..., 1] / np.sqrt(dist2)
    want = (intensity * np.maximum(cos, 0) / dist2).sum(-1) / math.pi     # rho = 1
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    got = mean_image(scene, rv.graphs.hybrid(preset="raw"), views, "Composite.color", 48)[..., 0]
    assert abs(got.mean() / want.mean() - 1.0) < 0.03, (got.mean(), want.mean())


def test_a_spot_that_does_not_reach_a_point_takes_none_of_its_light_samples(gpu):
    """A sun (E = 2 lux, straight down) and a narrow bright spot aimed off the plane's centre: in a
    scene of few punctual lights the light is drawn by its unshadowed irradiance at the point, so a
    pixel outside the spot's cone gets the sun's rho E / pi in every frame (drawn by power alone,
    over a quarter of the samples went to the spot and left those pixels black), and the mean
    inside the cone is still the float64 sum of both lights."""
    scene = plane_scene(albedo=0.5)
    spot_at = np.array([0.6, 0.0, 0.6])
    spot_pos = spot_at + np.array([0.0, 1.0, 0.0])
    scene.lights = [Light("directional", direction=(0.0, -1.0, 0.0), intensity=2.0),
                    Light("spot", position=spot_pos, direction=(0.0, -1.0, 0.0), intensity=200.0,
                          inner_cone_angle=0.15, outer_cone_angle=0.2)]
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    views = down_view()
    pts = plane_points(views)
    to = spot_pos[None, None] - pts
    dist = np.linalg.norm(to, axis=-1)
    cos_axis = to[..., 1] / dist
    k = np.clip((cos_axis - math.cos(0.2)) / (math.cos(0.15) - math.cos(0.2)), 0, 1)
    spot = 200.0 * k * k / dist ** 2 * cos_axis            # irradiance on the plane (cos at the plane = cos_axis)
    sun = 0.5 / math.pi * 2.0
    outside, inside = cos_axis < math.cos(0.2) - 0.01, k > 0.99
    assert outside.sum() > 100 and inside.sum() >= 4
    frames = []
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=views) as r:
        for _ in range(16):
            r.render()
            frames.append(r.read_output("Composite.color")[0, ..., 0].astype(np.float64))
    frames = np.array(frames)
    np.testing.assert_allclose(frames[:, outside], sun, rtol=2e-3)
    want = sun + 0.5 / math.pi * spot[inside]
    np.testing.assert_allclose(frames.mean(0)[inside], want, rtol=0.15)


@pytest.mark.parametrize("albedo", [0.5, 0.01])
@pytest.mark.parametrize("effect", [rv.Effect.RASTER, rv.Effect.SHADOWS, rv.Effect.PATH_TRACED])
def test_lambert_plane_under_a_uniform_environment_is_albedo_times_radiance(gpu, effect, albedo):
    """Nothing above the plane: its radiance is rho L exactly, in the raster pass (unshadowed
    environment), the shadow pass and the path tracer; a dark albedo too (the G-buffer's base colour
    is float16: in rgba8, 0.01 would be stored as 3/255, 18% too bright)."""
    scene = plane_scene(albedo=albedo)
    scene.environment = Environment((2.0, 1.0, 0.5), name="uniform")
    for m in scene.materials:
        m.effect = effect
    got = mean_image(scene, rv.graphs.hybrid(preset="raw"), down_view(), "Composite.color", 32)
    np.testing.assert_allclose(got.mean(axis=(0, 1)), albedo * np.array([2.0, 1.0, 0.5]), rtol=0.02)


def test_path_traced_graph_sees_the_environment_on_the_plane_and_beyond(gpu):
    scene = plane_scene(albedo=0.5)
    scene.environment = Environment((1.0, 1.0, 1.0), name="uniform")
    views = ViewSet([View(look_at((0.0, 1.0, 3.0), (0.0, 0.0, 0.0)), Fov.symmetric(60.0, 1.0), SIZE, SIZE, 0.01, 10.0)])
    img = mean_image(scene, rv.graphs.path_traced(max_bounces=2), views, "Accumulate.dst", 16)[..., 0]
    sky, plane = img[img > 0.75], img[img < 0.75]
    assert len(sky) > 20 and len(plane) > 20
    # escaped rays bring the radiance itself (pixels on the horizon mix the two)
    assert np.median(sky) == pytest.approx(1.0, rel=1e-3)
    assert np.median(plane) == pytest.approx(0.5, rel=0.03)


def test_environment_files_that_are_not_panoramas_are_refused_naming_the_file(tmp_path):
    from PIL import Image

    square = tmp_path / "square.png"
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(square)
    with pytest.raises(SceneError, match=r"square\.png.*2:1"):
        load_environment(str(square))
    broken = tmp_path / "broken.exr"
    broken.write_bytes(b"not an image")
    with pytest.raises((SceneError, OptionError), match=r"broken\.exr"):
        load_environment(str(broken))
    with pytest.raises(OptionError, match="no such file"):
        load_environment(str(tmp_path / "missing.hdr"))
    with pytest.raises(OptionError, match="non-negative"):
        load_environment("1,-1,1")


@pytest.mark.parametrize("argv, field", [
    (["--environment", "{square}"], "2:1"),
    (["--graph", "path_traced", "--spp", "-4"], "--spp"),
    (["--graph", "path_traced", "--spp", "0"], "--spp"),
    (["--graph", "path_traced", "--bounces", "-1"], "--bounces"),
    (["--environment-strength", "-2"], "--environment-strength"),
    (["--light-selection", "nearest"], "--light-selection"),
])
def test_render_refuses_bad_lighting_options_in_one_line(gpu, tmp_path, capsys, argv, field):
    from PIL import Image

    square = tmp_path / "square.png"
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(square)
    out = tmp_path / "out"
    argv = [a.format(square=square) for a in argv]
    with pytest.raises(SystemExit) as exc:
        raise SystemExit(main(["render", "--size", "8x8", *argv, "--out", str(out / "x.png")]))
    err = capsys.readouterr().err.strip()
    assert exc.value.code == 2 and field in err and "Traceback" not in err
    assert len([line for line in err.splitlines() if line.startswith("rayvr: error")]) == 1
    assert not out.exists() or not any(out.iterdir())
