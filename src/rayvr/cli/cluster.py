"""`--workers N` / `--address ADDR` for the rayvr subcommands (render, converge, tune): the
options, the Cluster they ask for, and the subcommands' cluster paths. Nothing here imports Ray
unless the options ask for a cluster."""
from __future__ import annotations

import collections
import contextlib

from .options import integer, say_nonfinite

MAX_WORKERS = 1024


def add_arguments(parser) -> None:
    """Add --workers and --address to a subcommand's parser."""
    group = parser.add_argument_group("cluster (needs the cluster extra: pip install 'rayvr[cluster]')")
    group.add_argument("--workers", type=integer("--workers", 1, MAX_WORKERS), metavar="N",
                       help="split the work over N Ray workers, one GPU each (llvmpipe without GPUs)")
    group.add_argument("--address", metavar="ADDR",
                       help="an existing Ray cluster ('auto', host:6379, ray://host:10001); default: a local one")


def requested(args) -> bool:
    """Whether the options ask for a cluster."""
    return getattr(args, "workers", None) is not None or bool(getattr(args, "address", None))


def open_cluster(args):
    """The Cluster the options ask for (ClusterError with the install hint without Ray)."""
    from ..cluster.ray_support import require_ray

    require_ray("--workers" if args.workers is not None else "--address")
    from ..cluster.pool import Cluster

    return Cluster(args.workers, args.address)


def render(args, spec, scene, graph, views, hdr: bool, grid=None) -> tuple:
    """`rayvr render --workers`: the views split over the workers, each rendering `--frames`
    frames; linear radiance gathered and tone mapped here (auto exposure sees every view).
    Returns (pixels (views, h, w, c) rows top-down, the quilt's pixels when `grid` is given, else
    None) and prints what ran where; rayvr render writes them (all or nothing)."""
    from ..cluster.gather import tone_map
    from ..cluster.jobs import render_views
    from ..cluster.payload import ScenePayload, effects_of
    from ..graphs import hdr_output

    payload = ScenePayload.of(spec, effects_of(scene))
    pin = hdr_output(graph)   # the denoiser's, with --denoise
    with open_cluster(args) as cluster:
        result = render_views(scene, graph, views, pins=[pin], frames=args.frames, cluster=cluster,
                              payload=payload, progress=True)
    size = views.size
    print(f"{scene.name}: {len(views)} view(s) of {size[0]}x{size[1]}, {args.frames} frame(s) "
          f"on {len(result.shares)} worker share(s)")
    for share in result.shares:
        last = share["first_view"] + share["views"] - 1
        print(f"  views {share['first_view']}-{last}: {share['render_ms']:.2f} ms per frame (wall), "
              f"{share['worker']}")
    if getattr(args, "report", False):
        print("--report: each worker compiles its own graph; run without --workers for the compile report")
    nonfinite = collections.Counter()   # every share's passes, summed by pass
    for share in result.shares:
        nonfinite.update(share.get("nonfinite", {}))
    radiance = result.pixels[pin]
    if hdr and grid is None:
        say_nonfinite(nonfinite)
        return radiance, None
    tm = graph.get_pass("ToneMap")
    pixels, texture, compiled = tone_map(radiance, tm.operator, tm.exposure, tm.auto_exposure)
    try:
        quilt_pixels = None
        if grid is not None:
            from ..gpu import get_context
            from ..xr.quilt import compose_quilt, read_quilt

            quilt_pixels = read_quilt(compose_quilt(get_context().gl, texture, *grid))
        nonfinite.update(compiled.nonfinite_counts())   # the tone map of the gathered views
    finally:
        compiled.release()
    say_nonfinite(nonfinite)
    return (radiance if hdr else pixels), quilt_pixels


@contextlib.contextmanager
def study_runner(args, spec, scene, progress: bool = True):
    """Where `rayvr converge` and `rayvr tune` run the error study: here
    (rayvr.study.runner.LocalRunner), or with --workers/--address on the cluster
    (rayvr.cluster.StudyRunner: references split by samples, the probe on one worker, the
    configurations over all, each row naming the worker that timed it). `spec`: the scene as
    given on the command line (a glTF file travels as its bytes)."""
    if not requested(args):
        from ..study.runner import LocalRunner

        yield LocalRunner()
        return
    from ..cluster.payload import ScenePayload, effects_of
    from ..cluster.study import StudyRunner

    payload = ScenePayload.of(spec, effects_of(scene))
    with open_cluster(args) as cluster:
        yield StudyRunner(cluster, payload, progress)
