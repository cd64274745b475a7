"""A still view converges: every ray-traced term of the hybrid is carried across frames (TAA's
exact running mean while the view and the scene stay as they were, SVGF's unbounded history), so
the error against the configuration's own converged, pixel-filtered image falls about as 1/N; an
edit of the lighting or a moving head drops what no longer holds."""
import dataclasses

import numpy as np
import pytest

import rayvr as rv
from rayvr.scene.model import Light
from rayvr.xr.cameras import default_views
from rayvr.xr.views import Pose, ViewSet

SIZE = (32, 32)


def cornell(effect=rv.Effect.SHADOWS):
    scene = rv.scenes.cornell_box()
    for m in scene.materials:
        m.effect = effect
    return scene


def relmse(a, b, eps=1e-2):
    return float(((a - b) ** 2 / (b * b + eps)).mean())


def still_means(scene, graph, counts, first_frame=0, views=1, pin="TAA.dst", size=SIZE):
    """The graph's HDR output after each of `counts` frames of one still view set."""
    view_set = default_views(scene, views, size)
    out = {}
    with rv.Renderer(scene, graph, views=view_set, first_frame=first_frame) as r:
        done = 0
        for n in sorted(counts):
            while done < n:
                r.render()
                done += 1
            out[n] = r.read_output(pin, flip_y=True)[..., :3].astype(np.float64)
    return out


@pytest.mark.parametrize("preset", ["raw", "clean"])
def test_a_still_shadows_only_view_converges_to_its_own_converged_image(gpu, preset):
    """64 still frames at most a quarter of one frame's relMSE against the same configuration's
    converged image (an independent run of many frames: its own seeds and jitter positions)."""
    scene = cornell()

    def graph():
        return rv.graphs.hybrid(preset=preset, taa=True, probes={"counts": [2, 2, 2], "rays_per_probe": 32}
                                if preset == "clean" else None)

    runs = still_means(scene, graph(), (1, 16, 64))
    converged = still_means(scene, graph(), (384,), first_frame=100_000)[384]
    errors = {n: relmse(img, converged) for n, img in runs.items()}
    assert errors[64] <= 0.25 * errors[1], errors
    assert errors[64] < errors[16] < errors[1], errors
    assert all(np.isfinite(img).all() for img in runs.values())


def test_svgf_on_a_still_view_never_gets_worse_with_more_frames(gpu):
    """As the history's variance falls the a-trous filter backs off: the error against the
    configuration's converged image keeps falling from 16 to 64 to 128 frames."""
    scene = cornell()
    graph = lambda: rv.graphs.hybrid(preset="raw", denoise="svgf")   # noqa: E731
    runs = still_means(scene, graph(), (4, 16, 64, 128))
    converged = still_means(scene, graph(), (384,), first_frame=200_000)[384]
    errors = [relmse(runs[n], converged) for n in (4, 16, 64, 128)]
    assert errors == sorted(errors, reverse=True), errors
    assert errors[-1] < 0.3 * errors[1], errors


def test_taa_counts_the_still_frames_and_a_moving_head_starts_again(gpu):
    scene = cornell()
    view_set = default_views(scene, 1, SIZE)
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw", taa=True), views=view_set) as r:
        taa = r.compiled.passes["TAA"]
        for _ in range(5):
            r.render()
        assert taa.still_frames == 5   # the first frame, then four still ones
        v0 = view_set.views[0]
        pose = Pose(v0.pose.position + np.array([0.01, 0.0, 0.0]), v0.pose.orientation)
        moved = ViewSet([dataclasses.replace(v0, pose=pose)], previous=view_set)
        r.render(moved)
        assert taa.still_frames == 1
        r.render(moved)
        assert taa.still_frames == 2


def test_a_lighting_edit_drops_the_still_history_at_once(gpu):
    """A still view accumulates; then the light is made ten times brighter: the very next frame
    shows the new light (no 1/N blend with the old mean)."""
    scene = rv.scenes.cornell_box()
    for m in scene.materials:
        m.emissive = (0.0, 0.0, 0.0)
        m.effect = rv.Effect.SHADOWS
    scene.lights.append(Light("point", position=(0.0, 0.4, 0.0), intensity=0.2))
    view_set = default_views(scene, 1, SIZE)
    graph = rv.graphs.hybrid(preset="raw", taa=True)
    graph.update_pass("TAA", {"clamp": False})   # the drop alone, not the colour clamp, must do it
    with rv.Renderer(scene, graph, views=view_set) as r:
        for _ in range(8):
            r.render()
        before = r.read_output("TAA.dst")[..., :3].astype(np.float64)
        scene.lights[0].intensity = 2.0
        r.render()
        after = r.read_output("TAA.dst")[..., :3].astype(np.float64)
        lit = before > 1e-3
        np.testing.assert_allclose(np.median(after[lit] / before[lit]), 10.0, rtol=0.05)


@pytest.mark.slow
def test_the_default_render_of_the_cornell_box_is_within_one_percent_of_the_path_tracer(gpu, tmp_path, capsys):
    """`rayvr render --size 64x64 --frames 16` (the clean preset, two views) against a pixel-filtered
    path-traced reference of 2 x 512 samples per pixel: relMSE <= 0.01."""
    import OpenEXR

    from rayvr.cli.main import main

    out = tmp_path / "c.exr"
    assert main(["render", "--size", "64x64", "--frames", "16", "--out", str(out)]) == 0
    capsys.readouterr()
    got = []
    for eye in ("L", "R"):
        with OpenEXR.File(str(tmp_path / f"c_{eye}.exr")) as f:
            got.append(np.asarray(f.channels()["RGB"].pixels, np.float64))
    got = np.stack(got)
    scene = rv.scenes.cornell_box()
    g = rv.graphs.path_traced(samples_per_pixel=8, max_bounces=8)
    g.update_pass("PathTracer", {"pixel_jitter": True})
    with rv.Renderer(scene, g, views=default_views(scene, 2, (64, 64))) as r:
        for _ in range(64):
            r.render()
        ref = r.read_output("Accumulate.dst", flip_y=True)[..., :3].astype(np.float64)
    assert np.isfinite(got).all()
    assert relmse(got, ref) <= 0.01
