"""CPU cost of CompiledGraph.execute() for a chain of passes with trivial GPU work.

Each frame: finish the GPU (not timed), then time execute() on the CPU. With timers on, the
timer method matters (the 'empty passes' row times the graph machinery alone): timer queries (GPU drivers) cost a query begin/end per pass; finish+wall
(llvmpipe) waits for the GPU inside execute(), so that row is not CPU overhead. Target: <= 0.3 ms
per frame for 10 passes, timers off and timer queries on.
"""
from __future__ import annotations

import time

import numpy as np

from rayvr.gpu import get_context

from ._graphs import linear_chain, null_chain

TARGET_MS = 0.3


def add_arguments(parser) -> None:
    parser.add_argument("--passes", type=int, default=10)
    parser.add_argument("--size", type=int, default=64, help="per-view width and height")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--frames", type=int, default=2000, help="timed frames per setting (quick: 30)")
    parser.add_argument("--warmup", type=int, default=50)


def measure(cg, ctx, frames: int, warmup: int) -> np.ndarray:
    gl = cg.gl
    for _ in range(warmup):
        cg.execute(ctx)
    gl.finish()
    times = np.empty(frames)
    for i in range(frames):
        gl.finish()
        t0 = time.perf_counter()
        cg.execute(ctx)
        times[i] = time.perf_counter() - t0
    gl.finish()
    return times * 1e3


def run(args) -> dict:
    frames, warmup = (30, 3) if args.quick else (args.frames, args.warmup)
    gpu = get_context()
    size = (args.size, args.size)
    null = null_chain(args.passes).compile(size=size, views=args.views, gpu=gpu, profiling=False)
    cg = linear_chain(args.passes).compile(size=size, views=args.views, gpu=gpu)
    ctx = cg.make_context()
    rows = []
    for graph, profiling, what in ((null, False, "empty passes"), (cg, False, "Clear+Blits"),
                                   (cg, True, "Clear+Blits")):
        graph.set_profiling(profiling)
        ms = measure(graph, ctx, frames, warmup)
        method = graph.timing_method
        # llvmpipe runs each dispatch synchronously, so only the machinery row is CPU overhead there.
        counts = method in ("off", "timer-query") and not (gpu.caps.is_software and graph is cg)
        rows.append([what, ("on" if profiling else "off"), method, args.passes, f"{args.size}x{args.size}x{args.views}",
                     frames, round(float(ms.mean()), 4), round(float(np.median(ms)), 4),
                     round(float(np.percentile(ms, 95)), 4), round(float(ms.min()), 4),
                     round(1e3 * float(ms.mean()) / args.passes, 2), TARGET_MS,
                     ("yes" if ms.mean() <= TARGET_MS else "NO") if counts else "n/a (includes GPU work)"])
    cg.release()
    null.release()
    return {
        "columns": ["passes_kind", "timers", "method", "passes", "size", "frames", "mean_ms", "median_ms", "p95_ms",
                    "min_ms", "us_per_pass", "target_ms", "meets"],
        "rows": rows,
        "notes": ["CPU time inside execute(); the GPU is finished before each timed frame",
                  "'empty passes' is the graph machinery alone; llvmpipe runs compute dispatches "
                  "synchronously, so its Clear+Blits rows include the GPU work"],
    }
