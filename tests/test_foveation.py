"""A foveated ray budget (hybrid(foveation='fixed'|'gaze'), rayvr.xr.foveation): the trace
decision's budget map is the formula's, a pixel gets its turns on exactly its share of 64 frames,
the foveal region renders as without foveation, the periphery traces fewer rays, and a gaze moved
to a corner moves the dense region there (a simulated eye tracker, fixations and saccades)."""
import math

import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError, XrError
from rayvr.passes import TraceDecision
from rayvr.renderer import Renderer
from rayvr.xr import foveation
from rayvr.xr.gaze import GazePath, gaze_tangents, saccade_duration

from decision_scenes import DECISION, FILL, NONE, TRACE, decision_graph, lambert_cornell

SIZE = (48, 48)


def graph(**kw):
    return decision_graph(**kw)


def test_the_budget_formula():
    e = np.array([0.0, 5.0, 10.0, 20.0, 1e3])
    b = foveation.budget(e, 5.0, 0.25)
    assert b[:2].tolist() == [1.0, 1.0]
    assert b[2] == pytest.approx(0.25 + 0.75 / 4) and b[3] == pytest.approx(0.25 + 0.75 / 16)
    assert b[4] == pytest.approx(0.25, abs=1e-4)
    assert foveation.eccentricity_weight(20.0, 5.0) == pytest.approx(1 / 16)


def test_the_budget_map_matches_its_formula_and_each_pixel_gets_its_share_of_turns(gpu):
    """Over 64 frames (every rotation of the 8x8 dither) a pixel of budget b is selected on
    ceil(64 b - 1/2) frames; it traces then, and on others only where no neighbour could fill it."""
    scene = lambert_cornell()
    props = {"foveal_radius_deg": 6.0, "periphery_share": 0.125}
    views = rv.renderer.default_views(scene, 1, SIZE)
    traced = np.zeros((1, SIZE[1], SIZE[0]))
    with Renderer(scene, graph(foveation="fixed", decision=props), views=views) as r:
        for _ in range(64):
            r.render()
            t = r.read_output(DECISION)[..., 0]
            traced += (t & 3) == TRACE
        budget_map = ((t >> 8) & 0xFF) / 255.0
        kinds = t & 3
    expected = foveation.budget(foveation.eccentricity_map(views), 6.0, 0.125)
    assert np.abs(budget_map - expected).max() <= 0.5 / 255 + 1e-4   # 8 bits, float32 angles
    drawn = kinds != NONE
    turns = np.ceil(64 * expected - 0.5)   # +-1 where 64 b - 1/2 is within float32 rounding of a whole number
    assert (traced[drawn] >= turns[drawn] - 1).all()
    assert (np.abs(traced[drawn] - turns[drawn]) <= 1).mean() > 0.9   # the rest: surfaces too thin to fill from
    assert expected.min() < 0.3 and (kinds[drawn] == FILL).any()


def test_the_foveal_region_renders_as_without_foveation_with_fewer_rays(gpu):
    scene = lambert_cornell()
    views = rv.renderer.default_views(scene, 1, SIZE)
    out = {}
    for fov in (None, "fixed"):
        with Renderer(scene, graph(foveation=fov, decision={"foveal_radius_deg": 8.0} if fov else None),
                      views=views) as r:
            total = 0.0
            for _ in range(4):
                r.render()
                total = total + r.read_output("Composite.color")[..., :3].astype(np.float64)
            out[fov] = (total / 4, sum(r.compiled.ray_counts()))
    e = foveation.eccentricity_map(views)
    fovea = e < 8.0
    assert fovea.sum() > 100
    assert np.array_equal(out["fixed"][0][fovea], out[None][0][fovea])   # the same rays, the same light
    assert not np.array_equal(out["fixed"][0][~fovea], out[None][0][~fovea])
    assert out["fixed"][1] < 0.6 * out[None][1]


def corner_gaze(views_like, corner=(0.8, 0.8)):
    """The gaze (x, y degrees, head frame) through a point near the upper-right corner."""
    t = views_like[0].fov.tangents()
    tx, ty = t[0] + corner[0] * (t[1] - t[0]), t[2] + corner[1] * (t[3] - t[2])
    return math.degrees(math.atan(tx)), math.degrees(math.atan(ty))


def test_a_gaze_moved_to_a_corner_moves_the_dense_region(gpu):
    scene = lambert_cornell()
    headset = rv.xr.SimulatedHeadset(size=SIZE, frames=1)
    headset.place(rv.xr.camera_pose(scene)[0])
    views = headset.wait_frame().views
    gaze = corner_gaze(views)
    centres = {}
    for name, spec in (("centre", "centre"), ("corner", [(0.0, gaze)])):
        sink = rv.xr.SimulatedHeadset(size=SIZE, frames=2, gaze=spec)
        with Renderer(scene, graph(foveation="gaze"), sink=sink) as r:
            for frame in r.frames(1):
                tangents = frame.views.gaze
            budget = ((r.read_output(DECISION)[..., 0] >> 8) & 0xFF) / 255.0
        # the middle of the full-budget disc in each eye, and where the eye tracker said the eye looked
        peak = [np.argwhere(b == 1.0).mean(axis=0) for b in budget]
        centres[name] = (peak, tangents, budget)
    h, w = SIZE[1], SIZE[0]
    for eye in range(2):
        (y, x), t = centres["corner"][0][eye], views[eye].fov.tangents()
        gx, gy = centres["corner"][1][eye]
        assert abs(x + 0.5 - (gx - t[0]) / (t[1] - t[0]) * w) <= 1.5
        assert abs(y + 0.5 - (gy - t[2]) / (t[3] - t[2]) * h) <= 1.5
        assert x > 0.7 * w and y > 0.7 * h
        cy, cx = centres["centre"][0][eye]
        assert abs(cx - w / 2) < 0.15 * w and abs(cy - h / 2) < 0.15 * h
        corner = centres["corner"][2][eye]
        assert corner[-h // 4:, -w // 4:].mean() > 1.5 * corner[:h // 4, :w // 4].mean()


def test_a_gaze_path_holds_fixations_and_sweeps_saccades():
    path = GazePath([(0.0, (0.0, 0.0)), (1.0, (20.0, 0.0)), (2.0, (20.0, -10.0))])
    assert path.direction_at(-1.0) == (0.0, 0.0) and path.direction_at(0.5) == (0.0, 0.0)
    d = saccade_duration(20.0)
    assert d == pytest.approx(0.021 + 0.044)
    assert path.direction_at(1.0 - d - 1e-6) == (0.0, 0.0)     # still fixating before the saccade
    assert path.direction_at(1.0 - d / 2)[0] == pytest.approx(10.0)   # halfway in the middle
    assert path.direction_at(1.0) == (20.0, 0.0) and path.direction_at(9.0) == (20.0, -10.0)
    with pytest.raises(XrError, match="times must increase"):
        GazePath([(1.0, (0, 0)), (0.5, (1, 1))])
    with pytest.raises(XrError, match="fixation 0"):
        GazePath([(0.0, "up")])


def test_gaze_tangents_in_each_eye():
    views = rv.xr.stereo_views(rv.xr.Pose(), 0.064, rv.xr.Fov.symmetric(90, 1.0), rv.xr.Fov.symmetric(90, 1.0),
                               (8, 8))
    t = gaze_tangents(views, np.eye(3), (30.0, -10.0))
    assert np.allclose(t, [[math.tan(math.radians(30)), math.tan(math.radians(-10))]] * 2)
    views.gaze = t
    assert views.gaze_tangents()[1] is True
    with pytest.raises(XrError, match="gaze"):
        views.gaze = np.zeros((3, 2))


def test_bad_foveation_input_is_one_clear_error(gpu):
    with pytest.raises(OptionError, match="foveation='peripheral'"):
        rv.graphs.hybrid(foveation="peripheral")
    with pytest.raises(OptionError, match="TraceDecision.*periphery_share.*0.125"):
        TraceDecision(periphery_share=0.01)
    with pytest.raises(OptionError, match="foveal_radius_deg.*90"):
        TraceDecision(foveal_radius_deg=120.0)
    with pytest.raises(OptionError, match="TraceDecision.*'foveation'.*'gaze'"):
        TraceDecision(foveation="eyes")


def test_foveal_flip_judges_where_the_eye_looks():
    """FLIP within the foveal radius sees only an error there; the eccentricity-weighted FLIP
    counts a peripheral error less than the plain mean does."""
    from rayvr.study.display import Display
    from rayvr.study.metrics import all_metrics

    views = rv.xr.stereo_views(rv.xr.Pose(), 0.064, rv.xr.Fov.symmetric(90, 1.0), rv.xr.Fov.symmetric(90, 1.0),
                               (64, 64))
    ecc = foveation.eccentricity_map(views)[:, ::-1]
    rng = np.random.default_rng(1)
    reference = rng.uniform(0.2, 0.8, (2, 64, 64, 3))
    far, near = reference.copy(), reference.copy()
    far[ecc > 30.0] *= 0.3       # an error only in the periphery
    near[ecc < 4.0] *= 0.3       # ... only in the fovea
    which = ("flip", "flip_fovea", "flip_ecc")
    m_far = all_metrics(far, reference, Display(exposure=0.0), ppd=15, which=which, eccentricity=ecc)
    m_near = all_metrics(near, reference, Display(exposure=0.0), ppd=15, which=which, eccentricity=ecc)
    assert m_far["flip_fovea"] == 0.0 and m_far["flip"] > 0.01 and m_far["flip_ecc"] < 0.5 * m_far["flip"]
    assert m_near["flip_fovea"] > 10 * m_near["flip"] and m_near["flip_ecc"] > m_near["flip"]
    with pytest.raises(OptionError, match="eccentricity"):
        all_metrics(far, reference, Display(exposure=0.0), which=which)


def test_render_command_takes_the_trace_options_and_reports_them(gpu, tmp_path, capsys):
    from rayvr.cli.main import main

    code = main(["render", "--size", "24x24", "--preset", "raw", "--effect", "*=shadows", "--reuse", "views",
                 "--foveation", "fixed", "--foveal-radius", "6", "--periphery-share", "0.5", "--report",
                 "--out", str(tmp_path / "f.png")])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "fixed: every pixel within 6 degrees of each view's centre" in out and "falling to 0.5" in out
    assert "views reuse rough surfaces" in out
    line = next(l for l in out.splitlines() if "rays traced (last frame)" in l)
    first, second = (int(n) for n in line.split("per view")[1].split(","))
    assert second < 0.3 * first
    for argv, words in ((["--foveation", "eyes"], "invalid choice"),
                        (["--periphery-share", "0.5"], "--periphery-share shapes the foveation"),
                        (["--foveation", "fixed", "--periphery-share", "0.05"], "--periphery-share 0.05")):
        code = main(["render", "--size", "8x8", "--out", str(tmp_path / "x.png"), *argv])
        _, err = capsys.readouterr()
        assert code == 2 and words in err and "Traceback" not in err


def test_the_viewer_turns_foveation_on_as_a_graph_option(gpu):
    pytest.importorskip("imgui_bundle", reason="the viewer extra is not installed: pip install 'rayvr[viewer]'")
    from rayvr.viewer.app import Viewer
    from rayvr.viewer.offscreen import OffscreenSurface

    with Viewer(lambert_cornell(), "hybrid", views=2, size=(16, 16), surface=OffscreenSurface((32, 16), gpu)) as v:
        v.set_graph_option("foveation", "fixed")
        v.step()
        assert "Decision" in v.renderer.compiled.order and v.renderer.profile().rays_per_view
        v.set_graph_option("foveation", "none")
        v.step()
        assert "Decision" not in v.renderer.graph.passes
