"""GPU ms per compute dispatch inside the passes: where a pass's time goes among its stages.

`dispatch_ms(renderer, frames)` renders `frames` frames with the per-pass timers off (GL's
time-elapsed queries do not nest) and every compute dispatch (`ComputeShader.run` and
`run_indirect`) inside its own query, and returns the mean GPU ms per frame of each
"Pass/shader" (the shader's file; `#2`, `#3` for further programs of one file, such as another
stage or variant). A tool for benchmarks on a GPU with timer queries; the query per dispatch costs
a little, so its sum runs slightly above the per-pass profile.
"""
from __future__ import annotations

import contextlib
from collections import defaultdict

import moderngl

import rayvr.gpu.shaders as shaders


class _Recorder:
    """Labels the programs compiled while it is installed and times their dispatches."""

    def __init__(self):
        self.gl = None   # the renderer's, set by dispatch_ms
        self.labels: dict[int, str] = {}
        self._per_file: dict[str, list[int]] = defaultdict(list)
        self.current_pass = "?"
        self.active = False
        self.pending: list[tuple[str, object]] = []
        self._free: list = []

    def label(self, prog, sources) -> None:
        if id(prog) in self.labels:
            return
        name = next(iter(sources.values())).files[0].name
        same = self._per_file[name]
        same.append(id(prog))
        self.labels[id(prog)] = name if len(same) == 1 else f"{name}#{len(same)}"

    def timed(self, prog, dispatch):
        if not self.active:
            return dispatch()
        q = self._free.pop() if self._free else self.gl.query(time=True)
        with q:
            out = dispatch()
        self.pending.append((f"{self.current_pass}/{self.labels.get(id(prog), 'unlabelled')}", q))
        return out

    def collect(self) -> dict[str, float]:
        """This frame's ms per label (waits for the queries)."""
        out: dict[str, float] = defaultdict(float)
        for key, q in self.pending:
            out[key] += q.elapsed / 1e6
            self._free.append(q)
        self.pending = []
        return out


@contextlib.contextmanager
def labelled_programs():
    """While open, compiled programs are labelled by their file (open it before the Renderer
    compiles its graph) and `ComputeShader` dispatches go through the recorder it yields."""
    rec = _Recorder()
    compile_, run, run_indirect = shaders._compile, moderngl.ComputeShader.run, moderngl.ComputeShader.run_indirect

    def labelled_compile(gl_, kind, sources, make):
        prog = compile_(gl_, kind, sources, make)
        rec.label(prog, sources)
        return prog

    def timed_run(self, *a, **k):
        return rec.timed(self, lambda: run(self, *a, **k))

    def timed_indirect(self, *a, **k):
        return rec.timed(self, lambda: run_indirect(self, *a, **k))

    shaders._compile = labelled_compile
    moderngl.ComputeShader.run, moderngl.ComputeShader.run_indirect = timed_run, timed_indirect
    try:
        yield rec
    finally:
        shaders._compile = compile_
        moderngl.ComputeShader.run, moderngl.ComputeShader.run_indirect = run, run_indirect


def dispatch_ms(renderer, rec: _Recorder, frames: int) -> dict[str, float]:
    """Mean GPU ms per frame of each Pass/shader over `frames` frames (profiling restored after)."""
    compiled = renderer.compiled
    rec.gl = compiled.gl
    was = compiled.profiling
    compiled.set_profiling(False)
    steps = compiled._steps
    names = list(compiled.order)

    def in_pass(name, run):
        def wrapped(ctx, data):
            rec.current_pass = name
            return run(ctx, data)
        return wrapped

    compiled._steps = [(in_pass(n, run), data, bits) for n, (run, data, bits) in zip(names, steps)]
    total: dict[str, float] = defaultdict(float)
    rec.active = True
    try:
        for _ in range(frames):
            renderer.render()
            for key, value in rec.collect().items():
                total[key] += value / frames
    finally:
        rec.active = False
        compiled._steps = steps
        compiled.set_profiling(was)
    return dict(total)


def dispatch_cell(times: dict[str, float]) -> str:
    """`Pass/shader ms` pairs in frame order."""
    return " ".join(f"{k} {v:.3f}" for k, v in times.items())
