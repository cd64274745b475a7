"""rayvr.cluster without Ray: share splits, the speed re-split, scene payloads, pinned views,
trajectory views, the worker's jobs in this process, progress counting, and the one-line
refusal when the cluster extra is missing."""
import sys

import numpy as np
import pytest

import rayvr as rv
from rayvr.cluster import PinnedViews, RenderWorker, ScenePayload, TrajectoryViews
from rayvr.cluster.host_split import WorkerSpeed, rebalanced
from rayvr.cluster.progress import ProgressCounter
from rayvr.cluster.shares import split_by_weights, split_evenly, view_range
from rayvr.cluster.study import _cut
from rayvr.errors import ClusterError
from rayvr.xr.cameras import default_views
from rayvr.study import seeds
from test_scene_gltf import base_doc, write


def test_split_evenly_covers_in_order_and_differs_by_at_most_one():
    for total, parts in [(10, 3), (4, 2), (3, 8), (1, 1), (48, 5)]:
        ranges = split_evenly(total, parts)
        assert ranges[0][0] == 0 and ranges[-1][1] == total
        assert all(a[1] == b[0] for a, b in zip(ranges, ranges[1:]))
        sizes = [b - a for a, b in ranges]
        assert max(sizes) - min(sizes) <= 1 and min(sizes) >= 1 and len(ranges) == min(total, parts)


def test_reference_shares_cover_the_frames_and_never_straddle_a_half_or_the_bounce_check():
    for frames, check, pieces in [(8, 2, 8), (32, 8, 8), (2, 1, 8), (256, 64, 3), (10, 5, 4), (64, 16, 1)]:
        bounds = [0, check, frames // 2, frames]
        ranges = _cut(bounds, pieces)
        assert ranges[0][0] == 0 and ranges[-1][1] == frames
        assert all(a[1] == b[0] and a[0] < a[1] for a, b in zip(ranges, ranges[1:]))
        assert not any(a < bound < b for a, b in ranges for bound in bounds)
        assert len({*bounds}) - 1 <= len(ranges) <= pieces + 3      # about `pieces`, one per segment at least
    assert _cut([0, 2, 4, 8], 8) == [(i, i + 1) for i in range(8)]


def test_split_by_weights_is_proportional_and_keeps_everyone_busy():
    assert split_by_weights(64, [1, 1]) == [32, 32]
    assert split_by_weights(64, [3, 1]) == [48, 16]
    assert split_by_weights(10, [1, 1, 1]) in ([4, 3, 3], [3, 4, 3], [3, 3, 4])
    assert split_by_weights(4, [100, 1, 1, 1]) == [1, 1, 1, 1]   # each at least one view
    assert sum(split_by_weights(7, [0.3, 2.9, 1.1])) == 7


def speed(**by_count):
    s = WorkerSpeed()
    for views, ms in by_count.items():
        s.observe(int(views[1:]), ms)
    return s


def test_rebalance_follows_speed_with_hysteresis():
    # worker 1 takes twice as long per view: it should get half as many views
    assert rebalanced([32, 32], [speed(n32=32.0), speed(n32=64.0)]) == [43, 21]
    # nearly equal speeds: a re-split would gain less than 5%, keep the shares
    assert rebalanced([32, 32], [speed(n32=32.0), speed(n32=32.6)]) == [32, 32]
    # equal workers with a fixed cost per frame, seen at 1 and 3 views: back to even
    equal = [speed(n1=3.0, n2=4.0), speed(n3=5.0, n2=4.0)]
    assert [s.line() for s in equal] == [pytest.approx((2.0, 1.0))] * 2
    assert rebalanced([1, 3], equal) == [2, 2]
    # ms per view alone reads the 1-view worker as the slower one: one view moves to probe the
    # fixed cost; once both have their line, nothing moves
    assert rebalanced([1, 3], [speed(n1=3.0), speed(n3=5.0)]) == [2, 2]
    assert rebalanced([2, 2], equal) == [2, 2]


def test_payloads_rebuild_the_scene_with_its_effects(tmp_path):
    doc, blob = base_doc()
    path = write(tmp_path, doc, blob)          # scene.gltf + data.bin: the buffer is a separate file
    p = ScenePayload.of(str(path), effects={"Red": "reflections"})
    assert set(p.files) == {"scene.gltf", "data.bin"}
    scene = p.load()
    assert scene.materials["Red"].effect == rv.Effect.REFLECTIONS and len(scene.meshes) == 1
    b = ScenePayload.of("box_on_plane")
    assert b.kind == "builtin" and b.load().name == "box_on_plane"
    cornell = rv.scenes.cornell_box()
    cornell.materials["Floor"].effect = rv.Effect.PATH_TRACED
    again = ScenePayload.of(cornell).load()
    assert again.materials["Floor"].effect == rv.Effect.PATH_TRACED
    assert ScenePayload.of(cornell).key == ScenePayload.of(cornell).key != b.key


def test_pinned_views_pack_each_view_as_the_whole_frame_does():
    scene = rv.scenes.cornell_box()
    views = default_views(scene, 4, (16, 16))
    whole = np.frombuffer(views.pack(), np.float32)[4:].reshape(4, -1)
    part = view_range(views, 2, 4)
    assert isinstance(part, PinnedViews) and np.array_equal(part.origin(), views.origin())
    assert np.array_equal(np.frombuffer(part.pack(), np.float32)[4:].reshape(2, -1), whole[2:])


def test_trajectory_views_follow_the_head_and_keep_the_rig():
    scene = rv.scenes.cornell_box()
    base = default_views(scene, 4, (16, 16))
    still = TrajectoryViews(base, "still", frames=3)
    for a, b in zip(still.views_at(2), base):
        assert np.allclose(a.pose.matrix(), b.pose.matrix(), atol=1e-12)
    turn = TrajectoryViews(base, "turn", frames=90, fps=90)
    moved = turn.views_at(30)        # a third of a second into the head shake
    gaps = [np.linalg.norm(moved[i].pose.position - moved[0].pose.position) for i in range(4)]
    base_gaps = [np.linalg.norm(base[i].pose.position - base[0].pose.position) for i in range(4)]
    assert np.allclose(gaps, base_gaps, atol=1e-9)            # the grid moves rigidly
    assert not np.allclose(moved[0].pose.orientation, base[0].pose.orientation)


def test_worker_views_and_samples_in_this_process_equal_a_renderer(gpu):
    scene = rv.scenes.box_on_plane()
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS
    views = default_views(scene, 4, (16, 16))
    payload = ScenePayload.of(scene)
    worker = RenderWorker("local", gpu=gpu)
    graph = rv.graphs.hybrid(preset="raw").to_dict()
    got = worker.run("views", (payload.key, [payload]), None, graph=graph, views=view_range(views, 1, 3),
                     pins=["Composite.color"])
    with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), views=views) as r:
        r.render()
        whole = r.read_output("Composite.color", flip_y=True)
    assert np.array_equal(got["pixels"]["Composite.color"], whole[1:3])
    assert "Shadows" in got["nonfinite"] and not any(got["nonfinite"].values())   # each share's own counts
    pt = rv.study.reference.reference_graph(rv.tune.ReferenceSettings(4, 1, 2))   # the reference's own graph
    two = default_views(scene, 1, (16, 16))
    start = seeds.reference_first_frame()                     # the study's reference seeds
    first = worker.run("samples", (payload.key, [payload]), None, graph=pt.to_dict(), views=two, first_frame=start,
                       frames=2, pin="Accumulate.dst")
    second = worker.run("samples", (payload.key, [payload]), None, graph=pt.to_dict(), views=two,
                        first_frame=start + 2, frames=2, pin="Accumulate.dst")
    one = rv.tune.render_reference(scene, two, rv.tune.ReferenceSettings(4, 1, 2), gpu=gpu)
    merged = (first["mean"] * 2 + second["mean"] * 2) / 4     # the shares' frames are one process's frames
    assert np.allclose(merged, one.image, rtol=1e-5, atol=1e-6)
    assert np.allclose(first["mean"], one.half_a, rtol=1e-5, atol=1e-6)   # half A: the first share's frames
    worker.close()


def test_progress_counter_counts_each_share_once():
    c = ProgressCounter()
    c.add((0, 0), 3)
    c.add((0, 1), 2)
    c.add((1, 0), 7)          # another job
    c.reset((0, 1))           # share 1 re-runs from the start
    c.add((0, 1), 4)
    assert c.total(0) == 7 and c.total(1) == 7
    c.clear(0)
    assert c.total(0) == 0


def test_without_ray_the_cluster_names_the_extra(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "ray", None)          # `import ray` raises ImportError
    import rayvr.cluster as rc

    with pytest.raises(ClusterError, match=r"^rayvr.cluster needs the cluster extra: pip install 'rayvr\[cluster\]'$"):
        rc.Cluster()
    from rayvr.cli.main import main

    out = tmp_path / "x.png"
    code = main(["render", "--views", "1", "--size", "8x8", "--workers", "2", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.strip() == "rayvr: error: --workers needs the cluster extra: pip install 'rayvr[cluster]'"
    assert not list(tmp_path.iterdir())                    # nothing written


def test_render_with_workers_sums_the_shares_non_finite_counts(gpu, monkeypatch, capsys):
    """`rayvr render --workers`: the shares' counts of scrubbed samples, summed by pass, reach
    stderr as one line each (as without workers)."""
    import argparse
    import contextlib

    from rayvr.cli import cluster as cluster_cli
    from rayvr.cluster import jobs

    scene = rv.scenes.quad()
    views = default_views(scene, 2, (8, 8))
    radiance = np.zeros((2, 8, 8, 4), np.float32)
    shares = [{"first_view": 0, "views": 1, "render_ms": 1.0, "worker": "w0", "nonfinite": {"Direct": 2, "ToneMap": 0}},
              {"first_view": 1, "views": 1, "render_ms": 1.0, "worker": "w1", "nonfinite": {"Direct": 3, "ToneMap": 0}}]
    monkeypatch.setattr(cluster_cli, "open_cluster", lambda args: contextlib.nullcontext(None))
    monkeypatch.setattr(jobs, "render_views", lambda *a, **k: jobs.ViewsResult({"Composite.color": radiance}, shares, 0.0))
    args = argparse.Namespace(frames=1, report=False)
    cluster_cli.render(args, "quad", scene, rv.graphs.hybrid(preset="raw"), views, hdr=True)
    err = capsys.readouterr().err
    assert err == "rayvr: warning: 5 non-finite samples in pass Direct were set to 0\n"


class _ReleasingRay:
    """Ray as a Cluster sees it just after another closed: its one GPU comes back after `polls`."""

    def __init__(self, polls: int, total: float = 1.0):
        self.polls, self.total, self.calls = polls, total, 0

    def cluster_resources(self):
        return {"GPU": self.total, "CPU": 16.0}

    def available_resources(self):
        self.calls += 1
        return {"GPU": self.total if self.calls > self.polls else 0.0, "CPU": 16.0}


def test_workers_wait_for_a_gpu_that_ray_is_still_releasing():
    from rayvr.cluster.pool import worker_shares

    ray = _ReleasingRay(polls=3)
    assert worker_shares(ray, 2, None, wait_s=5.0)[:2] == (2, 0.5)   # two workers share the one GPU
    assert ray.calls == 4
    assert worker_shares(_ReleasingRay(polls=2), 1, 1.0, wait_s=5.0)[:2] == (1, 1.0)
    with pytest.raises(ClusterError, match="all in use; free one or wait"):
        worker_shares(_ReleasingRay(polls=10**9), 2, None, wait_s=0.3)
    with pytest.raises(ClusterError, match="2 workers x 1 GPU need 2 GPUs; the cluster has 1 free"):
        worker_shares(_ReleasingRay(polls=0), 2, 1.0, wait_s=0.3)
