"""The graph builders of rayvr.graphs: path_traced() renders and accumulates, hybrid_taa() puts
TAA after the composite and reprojects with the G-buffer's motion vectors; the benchmark smoke-runs."""
import dataclasses

import numpy as np
import pytest

from rayvr.graphs import hybrid_taa, path_traced
from rayvr.renderer import Renderer
from rayvr.scene import builtin
from rayvr.scene.model import Camera
from rayvr.xr.cameras import default_views
from rayvr.xr.views import Pose, ViewSet


def test_path_traced_graph_accumulates_and_tone_maps(gpu):
    lamp = builtin.lambert("Lamp", (0.5, 0.5, 0.5), emissive=(1.0, 0.5, 0.25), emissive_strength=3.0)
    scene = builtin.quad(size=1.0, material=lamp)   # covers pixels 3.2 .. 12.8 of 16
    with Renderer(scene, path_traced(samples_per_pixel=2), size=(16, 16)) as r:
        for _ in range(3):
            r.render()
        assert r.compiled.plan.order == ["PathTracer", "Accumulate", "ToneMap"]
        assert r.compiled.passes["Accumulate"].frame_count == 3
        hdr = r.read_output("Accumulate.dst")
        ldr = r.read_output("ToneMap.dst")
        report = str(r.report())
    np.testing.assert_allclose(hdr[0, 4:12, 4:12, :3], np.broadcast_to([3.0, 1.5, 0.75], (8, 8, 3)), rtol=1e-6)
    assert ldr.dtype == np.uint8 and ldr.shape == (1, 16, 16, 4)
    assert (ldr[0, 8, 8, :3] > ldr[0, 0, 0, :3]).all()
    assert "PT_FROM_GBUFFER" in report


def test_path_traced_graph_restarts_when_the_camera_moves(gpu):
    scene = builtin.cornell_box()
    with Renderer(scene, path_traced(max_bounces=1), size=(16, 16)) as r:
        vs = default_views(scene, 1, (16, 16))
        r.render(vs)
        r.render(vs)
        acc = r.compiled.passes["Accumulate"]
        assert acc.frame_count == 2
        v = vs[0]
        moved = ViewSet([dataclasses.replace(v, pose=Pose(v.pose.position + [0.01, 0, 0], v.pose.orientation))])
        r.render(moved)
        assert acc.frame_count == 1


def _moving_camera_frames(graph, size=(32, 32)):
    scene = builtin.plane_with_point_light(height=1.0, intensity=2.0)
    scene.cameras[:] = [Camera.look_at((0, 2, 2), (0, 0, 0))]
    with Renderer(scene, graph, size=size, jitter=False) as r:   # reprojection alone, no jitter
        first = default_views(scene, 1, size)
        r.render(first)
        v = first[0]
        moved = dataclasses.replace(v, pose=Pose(v.pose.position + np.array([0.15, 0.0, 0.0]), v.pose.orientation))
        r.render(ViewSet([moved], previous=first))
        taa = r.read_output("TAA.dst")[0, 4:-4, 4:-4, 0].astype(np.float64)
        current = r.read_output("Composite.color")[0, 4:-4, 4:-4, 0].astype(np.float64)
        return taa, current, r.compiled.plan


def test_hybrid_taa_reprojects_with_gbuffer_motion_vectors(gpu):
    g = hybrid_taa(preset="raw", alpha=0.5)
    g.get_pass("TAA").set_properties({"clamp": False})   # reprojection alone
    taa, current, plan = _moving_camera_frames(g)
    assert plan.order.index("Composite") < plan.order.index("TAA") < plan.order.index("ToneMap")
    # the lit plane reprojected by its motion vectors agrees with this frame's shading
    np.testing.assert_allclose(taa, current, atol=2e-3)
    # the same frames without motion vectors blend mismatched pixels
    still = hybrid_taa(preset="raw", alpha=0.5)
    still.get_pass("TAA").set_properties({"clamp": False})
    still.remove_edge("GBuffer.motion", "TAA.motion")
    taa_still, current_still, _ = _moving_camera_frames(still)
    assert np.abs(taa_still - current_still).max() > 10 * np.abs(taa - current).max()


def test_path_tracing_benchmark_quick_run(tmp_path):
    import argparse
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))   # the repository root holds benchmarks/
    from benchmarks import path_tracing

    parser = argparse.ArgumentParser()
    path_tracing.add_arguments(parser)
    args = parser.parse_args(["--spp", "1", "--views", "1,2", "--reference-frames", "2"])
    args.quick = True
    result = path_tracing.run(args)
    assert len(result["rows"]) == 2
    row = dict(zip(result["columns"], result["rows"][1]))
    assert row["views"] == 2 and row["Msamples_per_s"] > 0 and np.isfinite(row["relMSE_1frame"])


def test_hybrid_path_traced_pixels_match_the_full_screen_path_tracer(gpu):
    """From the G-buffer (hybrid) or from the camera through pixel centres: the same paths (same
    seeds), so the same radiance up to the G-buffer's float16 normals and the composite's rgba16f."""
    import rayvr as rv

    scene = builtin.cornell_box()
    for m in scene.materials:
        m.effect = rv.Effect.PATH_TRACED
    full = path_traced(max_bounces=3)
    full.get_pass("PathTracer").set_properties({"pixel_jitter": False})
    with Renderer(scene, full, size=(16, 16)) as r:
        for _ in range(16):
            r.render()
        want = r.read_output("Accumulate.dst")[..., :3].astype(np.float64)
    with Renderer(scene, rv.graphs.hybrid(preset="raw", path_bounces=3), size=(16, 16)) as r:
        for _ in range(16):
            r.render()
        assert "PathTracer" in r.compiled.plan.order
        got = r.read_output("Composite.color")[..., :3].astype(np.float64)
    assert got.mean() == pytest.approx(want.mean(), rel=0.01)
    assert np.abs(got - want).mean() < 0.01 * want.mean()


def test_graphs_round_trip_through_json_and_python(tmp_path):
    import json

    import rayvr as rv

    for g in (path_traced(samples_per_pixel=2, clamp=5.0, max_frames=100), hybrid_taa(preset="raw", alpha=0.2, sigma=1.5)):
        d = g.to_dict()
        assert rv.RenderGraph.from_dict(json.loads(json.dumps(d))).to_dict() == d
        for ext in ("py", "json"):
            assert rv.RenderGraph.load(g.save(tmp_path / f"{g.name}.{ext}")).to_dict() == d
