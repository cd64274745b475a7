"""Non-finite samples are counted: every pass that sets NaN/Inf radiance to 0 increments its GPU
counter (glsl/nonfinite.glsl, rayvr.rendergraph.nonfinite) once per sample it scrubbed; the
profile and the compile report show the totals and `rayvr render` says so on stderr.

NaNs are injected two ways: an EXR with NaN and Inf texels feeding the image passes (Accumulate,
TAA, ToneMap: each texel of each frame is one sample), and a directional light whose intensity is
made NaN in the GPU buffer after the first frame (the CPU light table stays finite), under which
every pixel of a Lambert plane that fills the view gets a NaN light sample: W x H x spp per frame
in the path tracer, W x H in DirectLighting, RTShadows and the hybrid's PathTracer.
"""
import numpy as np
import pytest

import rayvr as rv
from rayvr.passes.accumulate import Accumulate
from rayvr.passes.basic import ImageLoader
from rayvr.passes.taa import TAA
from rayvr.passes.tonemap import ToneMapper
from rayvr.renderer import Renderer
from rayvr.rendergraph import RenderGraph
from rayvr.rendergraph.nonfinite import nonfinite_lines
from rayvr.scene.builtin import lambert, quad_mesh
from rayvr.scene.gpu_frame import SceneFrame
from rayvr.scene.model import Environment, Light, Scene
from rayvr.xr.cameras import look_at
from rayvr.xr.views import Fov, View, ViewSet

W, H = 12, 10
INTENSITY_OFFSET = 16 * (1 + 2)   # bytes: the header row, then row 2 of light 0 (colour x intensity)


# ---- the image passes ---------------------------------------------------------------------------
def nan_image(tmp_path):
    """An EXR of W x H with 3 NaN texels, 2 +Inf and 1 -Inf (in one channel each): 6 bad samples."""
    OpenEXR = pytest.importorskip("OpenEXR")
    rgb = np.random.default_rng(0).random((H, W, 3)).astype(np.float32)
    for (y, x, c), v in zip([(0, 0, 0), (3, 4, 1), (9, 11, 2), (5, 5, 0), (2, 7, 2), (8, 1, 1)],
                            [np.nan, np.nan, np.nan, np.inf, np.inf, -np.inf]):
        rgb[y, x, c] = v
    path = tmp_path / "bad.exr"
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, {"RGB": rgb}) as f:
        f.write(str(path))
    return path, 6


def test_image_passes_count_each_bad_texel_of_each_frame_exactly(gpu, tmp_path):
    path, bad = nan_image(tmp_path)
    g = RenderGraph("nan")
    g.add_pass(ImageLoader(path=str(path)), "Image")
    g.add_pass(Accumulate(), "Accumulate")
    g.add_pass(TAA(), "TAA")
    g.add_pass(ToneMapper(operator="reinhard"), "ToneMap")
    g.add_edge("Image.dst", "Accumulate.src")
    g.add_edge("Image.dst", "TAA.color")
    g.add_edge("Image.dst", "ToneMap.src")
    for out in ("Accumulate.dst", "TAA.dst", "ToneMap.dst"):
        g.mark_output(out)
    views, frames = 2, 3
    cg = g.compile(size=(W, H), views=views, gpu=gpu)
    try:
        assert cg.nonfinite_counts() == {"Accumulate": 0, "TAA": 0, "ToneMap": 0}
        for _ in range(frames):
            cg.execute(cg.make_context())
        want = frames * views * bad
        # the profile answers without waiting: counts a frame or two old, caught up once the GPU is
        gpu.gl.finish()
        cg.profile()
        cg.execute(cg.make_context())
        gpu.gl.finish()
        caught_up = cg.profile().nonfinite
        want = (frames + 1) * views * bad
        assert caught_up == {"Accumulate": want, "TAA": want, "ToneMap": want}
        assert cg.nonfinite_counts() == caught_up
        # what they wrote is finite: the bad samples became 0
        for out in ("Accumulate.dst", "TAA.dst"):
            img = cg.read_output(out).astype(np.float64)
            assert np.isfinite(img).all(), out
            assert (img[:, H - 1, 0, 0] == 0).all(), out      # the NaN at file row 0 (GL row H - 1)
        profile = cg.profile()
        assert profile.nonfinite == {"Accumulate": want, "TAA": want, "ToneMap": want}
        assert f"Accumulate {want}, TAA {want}, ToneMap {want}" in str(profile)
        report = cg.report()
        assert report.nonfinite == profile.nonfinite
        assert f"non-finite samples set to 0 (GPU counters, as of this report): Accumulate {want}" in str(report)
        cg.reset_nonfinite()
        cg.execute(cg.make_context())
        assert cg.nonfinite_counts() == {"Accumulate": views * bad, "TAA": views * bad, "ToneMap": views * bad}
    finally:
        cg.release()


# ---- a NaN light in a scene ---------------------------------------------------------------------
def plane_scene(effect):
    s = Scene("nan light")
    s.add_material(lambert("Plane", (0.5, 0.5, 0.5), effect=effect))
    s.add_object("Plane", *quad_mesh([[-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]], (0, 1, 0)), "Plane")
    s.lights.append(Light("directional", direction=(0.2, -1.0, 0.1), intensity=2.0))
    s.environment = Environment((0.0, 0.0, 0.0), name="black")
    return s


def views_down():
    """A camera 1 m above the plane looking straight down: the plane fills the view."""
    return ViewSet([View(look_at((0.0, 1.0, 0.0), (0.0, 0.0, 0.0), up=(0, 0, -1)), Fov.symmetric(60.0, W / H),
                         W, H, 0.01, 100.0)])


def poison_light(renderer):
    renderer.gpu_scene.buffers["punctual_lights"].write(np.full(3, np.nan, np.float32).tobytes(),
                                                        offset=INTENSITY_OFFSET)


def counts_before_and_after(scene, graph, frames=3):
    """The counters after one clean frame, then after `frames` frames under the NaN light."""
    with Renderer(scene, graph, views=views_down()) as r:
        r.render()
        clean = r.compiled.nonfinite_counts()
        assert np.isfinite(r.read_output(rv.graphs.hdr_output(graph))).all()
        poison_light(r)
        for _ in range(frames):
            r.render()
        return clean, r.compiled.nonfinite_counts(), r.read_output(rv.graphs.hdr_output(graph))


@pytest.mark.parametrize("spp", [1, 3])
def test_path_tracer_counts_every_sample_under_a_nan_light(gpu, spp):
    g = rv.graphs.path_traced(samples_per_pixel=spp, max_bounces=2)
    clean, dirty, img = counts_before_and_after(plane_scene(rv.Effect.SHADOWS), g)
    assert set(clean) == {"PathTracer", "Accumulate", "ToneMap"} and not any(clean.values()), clean
    assert dirty == {"PathTracer": 3 * W * H * spp, "Accumulate": 0, "ToneMap": 0}
    assert np.isfinite(img).all()


@pytest.mark.parametrize("effect, counting", [(rv.Effect.RASTER, "Direct"), (rv.Effect.SHADOWS, "Shadows"),
                                              (rv.Effect.PATH_TRACED, "PathTracer")])
def test_hybrid_lighting_passes_count_every_pixel_under_a_nan_light(gpu, effect, counting):
    clean, dirty, img = counts_before_and_after(plane_scene(effect), rv.graphs.hybrid(preset="raw"))
    assert counting in clean and not any(clean.values()), clean
    assert dirty == {**{p: 0 for p in clean}, counting: 3 * W * H}, dirty
    assert np.isfinite(img).all()


def test_finite_scenes_report_zero_in_every_counting_pass(gpu):
    """box_on_plane through SVGF and TAA, and with probe GI and reflections: every counting pass
    is there and counted nothing."""
    scene = rv.scene.builtin.box_on_plane()
    graphs = {"svgf": (rv.graphs.hybrid(preset="raw", denoise="svgf"), rv.Effect.SHADOWS, {"SVGF", "TAA"}),
              "probes": (rv.graphs.hybrid_taa(preset="raw", gi="probes", probes={"counts": [2, 2, 2]}), rv.Effect.REFLECTIONS,
                         {"Probes", "Reflections", "TAA"})}
    for name, (graph, effect, extra) in graphs.items():
        for m in scene.materials:
            m.effect = effect
        with Renderer(scene, graph, views=2, size=(16, 16)) as r:
            for _ in range(2):
                r.render()
            counts = r.profile().nonfinite
        assert {"Direct", "Shadows", "ToneMap"} | extra <= set(counts), (name, counts)
        assert not any(counts.values()), (name, counts)


# ---- the CLI -----------------------------------------------------------------------------------
def test_nonfinite_lines_name_the_pass_and_count():
    assert nonfinite_lines({"PathTracer": 3, "ToneMap": 0, "TAA": 1}) == [
        "3 non-finite samples in pass PathTracer were set to 0",
        "1 non-finite sample in pass TAA was set to 0"]


def test_cli_render_says_when_samples_were_set_to_zero(gpu, tmp_path, capsys, monkeypatch):
    from rayvr.cli.main import main

    argv = ["render", "plane_with_point_light", "--graph", "path_traced", "--frames", "2", "--size", "8x8",
            "--views", "1"]
    assert main([*argv, "--out", str(tmp_path / "clean.png")]) == 0
    assert "non-finite" not in capsys.readouterr().err

    upload = SceneFrame._upload_lights

    def poisoned(self):   # every upload of the lights leaves the point light's intensity NaN
        changed = upload(self)
        if changed:
            self.gs.buffers["punctual_lights"].write(np.full(3, np.nan, np.float32).tobytes(), offset=INTENSITY_OFFSET)
        return changed

    monkeypatch.setattr(SceneFrame, "_upload_lights", poisoned)
    assert main([*argv, "--report", "--out", str(tmp_path / "nan.png")]) == 0
    out, err = capsys.readouterr()
    lines = [line for line in err.splitlines() if "non-finite" in line]
    # the camera looks down at the 4 m plane: every pixel's light sample is NaN, 2 frames x 64 pixels
    assert lines == ["rayvr: warning: 128 non-finite samples in pass PathTracer were set to 0"], err
    assert "non-finite samples set to 0 (all frames): PathTracer 128" in out                     # profile
    assert "non-finite samples set to 0 (GPU counters, as of this report): PathTracer 128" in out   # report
