"""The error study's image metrics in worker processes, while the GPU renders on.

At 2 x 1440x1600 one judged image costs ~100 CPU-seconds (88 of them HDR-FLIP, which runs
LDR-FLIP at each of the reference's exposures; SSIM and the tone mapping are single-threaded),
against milliseconds of GPU. `MetricPool` hands every judgement (rayvr.study.metrics.evaluate of
one read-back image) to a process pool sized by os.cpu_count() (less two for the process driving
the GPU and its driver) and gives back a `Pending` whose `get()` waits for it, so that the study renders the
next frames, configurations and curves while earlier images are judged. Results are those of
the same `evaluate` call in this process: each worker evaluates the whole image (views one after
the other, its own threads off), with the same inputs (the read-back float32 RGB values and the
reference), so that the serial path (`workers=0`: judged at once, here) and the parallel one give
identical numbers (tests/test_tune_pool.py).

References (the static one and one per trajectory frame) go to the workers once, as .npy files in
a temporary folder that each worker loads once and keeps (with its displayed image); test images travel with their task. At most
`2 x workers` judgements are outstanding: a render that would queue more waits for the oldest
(bounded memory: 55 MB per stereo 1440x1600 RGB float32 image). The study's progress bar
(rayvr.study.progress) counts metric work by the workers' own seconds, divided by the workers.
"""
from __future__ import annotations

import collections
import contextlib
import os
import signal
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from .display import clamp_negative

WORKER_NICENESS = 10   # the metric workers' scheduling priority below the study's own process
PARALLEL_VIEW_PIXELS = 256 * 256    # smaller views (llvmpipe's study sizes): the pool costs more than it saves


def default_workers(view_pixels: int) -> int:
    """Workers for views of `view_pixels` pixels: os.cpu_count() - 2, at least 1 (two cores stay
    with the process that drives the GPU and its driver's thread: with 15 workers on 16 cores a
    study's frames took 36-50 ms of wall time for 0.6 ms of GPU work; RAYVR_METRIC_WORKERS
    wins), 0 (judged here) below PARALLEL_VIEW_PIXELS."""
    env = os.environ.get("RAYVR_METRIC_WORKERS")
    if env is not None and env.strip():
        return max(0, int(env))
    return max(1, (os.cpu_count() or 1) - 2) if view_pixels >= PARALLEL_VIEW_PIXELS else 0


class Pending:
    """One judgement: `get()` -> (per-view metrics, maps, negative values)."""

    def __init__(self, pool, future=None, value=None, units: float = 0.0, label: str = ""):
        self.pool, self.future, self.value, self.units, self.label = pool, future, value, units, label

    def done(self) -> bool:
        return self.future is None or self.future.done()

    def get(self):
        if self.future is not None:
            self.pool.wait(self)
        return self.value


class MetricPool:
    """Judges images here (`workers=0`) or in `workers` processes; see the module docstring.

    `judge = pool.judge(image, reference_image, display, ppd, eps, names, which, maps, units)`
    returns a Pending; `progress` (a rayvr.study.progress.StudyProgress) is told of each judgement's
    `units` of kind "metric" (planned by the study) as it finishes."""

    def __init__(self, workers: int = 0, progress=None):
        from .progress import StudyProgress

        self.workers = max(0, int(workers))
        self.progress = progress or StudyProgress(False)
        self.executor = None
        self.outstanding: collections.deque[Pending] = collections.deque()
        self.folder = None
        self.refs: dict[int, tuple[np.ndarray, str]] = {}     # id(reference image) -> (image, .npy path)
        self.shown: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}   # (id, display) -> (image, displayed)
        self.worker_s = 0.0                                    # seconds the workers spent judging
        self.judged = 0

    def __enter__(self):
        if self.workers:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            # spawn, not fork: this process holds a GL context and the driver's threads
            self.executor = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"),
                                                initializer=_worker_init)
            self.folder = tempfile.TemporaryDirectory(prefix="rayvr-metrics-")
            self.progress.concurrent("metric", self.workers)
            for _ in range(self.workers):     # start the workers (imports) while the reference renders
                self.executor.submit(_ready)
        return self

    def __exit__(self, exc_type, *exc):
        if self.executor is not None:
            if exc_type is None:
                self.drain()
            if exc_type is not None:     # interrupted: stop the judging now (an HDR-FLIP takes a minute)
                for p in self.outstanding:
                    p.future.cancel()
                processes = list(getattr(self.executor, "_processes", {}).values())
                for process in processes:
                    process.terminate()
                for process in processes:
                    process.join(5)
            self.executor.shutdown(wait=exc_type is None, cancel_futures=exc_type is not None)
            self.executor = None
            self.folder.cleanup()
            self.progress.concurrent("metric", 0)

    @contextlib.contextmanager
    def quiet(self):
        """The workers stopped (SIGSTOP, where the OS has it) while the block runs, then continued:
        for timing the GPU. Timer queries count the GPU's idle time between a pass's commands, and
        busy workers starve the thread that submits them (timed while 14 workers judged, a study's
        rows read up to 1.7x their GPU time)."""
        stop = getattr(signal, "SIGSTOP", None)
        processes = list(getattr(self.executor, "_processes", {}).values()) if self.executor is not None else []
        stopped = []
        try:
            for process in processes if stop is not None else ():
                try:
                    os.kill(process.pid, stop)
                    stopped.append(process.pid)
                except (ProcessLookupError, PermissionError):
                    pass
            yield
        finally:
            for pid in stopped:
                try:
                    os.kill(pid, signal.SIGCONT)
                except (ProcessLookupError, PermissionError):
                    pass

    def _reference_path(self, reference: np.ndarray) -> str:
        key = id(reference)
        if key not in self.refs or self.refs[key][0] is not reference:
            path = Path(self.folder.name) / f"reference-{len(self.refs)}.npy"
            np.save(path, _rgb32(reference))
            self.refs[key] = (reference, str(path))
        return self.refs[key][1]

    def judge(self, image, reference, display, ppd, eps, names, which, maps: bool = False,
              units: float = 0.0, eccentricity=None) -> Pending:
        """Judge `image` against `reference` (both linear; negatives in `image` are judged as the
        display shows them, 0, and counted); `eccentricity` for the foveal metrics (metrics.evaluate)."""
        image, negatives = clamp_negative(image)
        label = names[0]
        if self.executor is None:
            with self.progress.step("metric", units, label):
                ref = _rgb32(reference)
                key = (id(reference), display)
                if key not in self.shown or self.shown[key][0] is not reference:
                    self.shown[key] = (reference, _shown(ref, display))
                per_view, m = _evaluate(_rgb32(image), ref, display, ppd, eps, names, which, maps, self.shown[key][1],
                                        eccentricity)
            return Pending(self, value=(per_view, m, negatives), units=units, label=label)
        while len(self.outstanding) >= 2 * self.workers:
            self.wait(self.outstanding[0])
        args = (_rgb32(image), reference, display, ppd, eps, tuple(names), tuple(which), maps, eccentricity)
        future = self.executor.submit(_judge_task, args[0], self._reference_path(reference), *args[2:])
        pending = Pending(self, future, units=units, label=label)
        pending.negatives, pending.args = negatives, args
        self.outstanding.append(pending)
        self.progress.in_flight("metric", units)
        return pending

    def wait(self, pending: Pending) -> None:
        """Block until `pending` is judged (the wait counts as the study's time)."""
        if pending.future is None:
            return
        from concurrent.futures.process import BrokenProcessPool

        try:
            if not pending.future.done():
                with self.progress.step("wait", 0.0, f"judging {pending.label}"):
                    pending.future.result()
            per_view, m, seconds = pending.future.result()
        except BrokenProcessPool:
            # e.g. a script without `if __name__ == "__main__":` (spawned workers import it again):
            # judge here instead, one after the other (the same numbers)
            warnings.warn("rayvr.tune: the metric worker processes failed to start or died; judging the images in "
                          "this process (guard your script's top level with `if __name__ == \"__main__\":` to use "
                          "them)", RuntimeWarning, stacklevel=2)
            self._serial_from_now()
            return
        pending.value, pending.future, pending.args = (per_view, m, pending.negatives), None, None
        self.outstanding.remove(pending)
        self.worker_s += seconds
        self.judged += 1
        self.progress.finished("metric", pending.units, seconds)

    def _serial_from_now(self) -> None:
        """The pool broke: every outstanding judgement is made here, and the next ones too."""
        executor, self.executor = self.executor, None
        executor.shutdown(wait=False, cancel_futures=True)
        self.folder.cleanup()
        self.workers = 0
        self.progress.concurrent("metric", 0)
        for p in list(self.outstanding):
            image, reference, display, ppd, eps, names, which, maps, eccentricity = p.args
            with self.progress.step("metric", p.units, p.label):
                ref = _rgb32(reference)
                per_view, m = _evaluate(image, ref, display, ppd, eps, names, which, maps, _shown(ref, display),
                                        eccentricity)
            p.value, p.future, p.args = (per_view, m, p.negatives), None, None
            self.outstanding.remove(p)

    def drain(self) -> None:
        """Wait for every outstanding judgement."""
        while self.outstanding:
            self.wait(self.outstanding[0])


def _rgb32(a) -> np.ndarray:
    """The first three channels as contiguous float32 (what evaluate reads of a read-back image)."""
    a = np.asarray(a)
    return np.ascontiguousarray(a[..., :3] if a.ndim == 4 and a.shape[-1] > 3 else a)


def _evaluate(image, reference, display, ppd, eps, names, which, maps, shown_reference, eccentricity=None):
    from .metrics import evaluate

    return evaluate(image, reference, display, ppd, eps, names=names, which=which, maps=maps,
                    shown_reference=shown_reference, eccentricity=eccentricity)


def _shown(reference, display):
    """The displayed reference, as evaluate makes it (None: the display needs none)."""
    from .metrics import pair

    return display(pair(reference, reference, ("reference", "reference"))[1])


# -- in the workers ---------------------------------------------------------------------------
_REFERENCES: dict[str, np.ndarray] = {}
_SHOWN: dict[tuple, np.ndarray] = {}


def _worker_init() -> None:
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    try:   # the process that drives the GPU comes first: its driver's waits yield the core
        os.nice(WORKER_NICENESS)
    except (AttributeError, OSError):
        pass
    from . import metrics

    metrics.THREADED_VIEW_PIXELS = float("inf")     # the pool is the parallelism: views one after the other


def _ready() -> int:
    import flip_evaluator  # noqa: F401  (imported once, before the first judgement)
    import skimage.metrics  # noqa: F401

    return os.getpid()


def _judge_task(image, reference_path, display, ppd, eps, names, which, maps, eccentricity=None):
    t0 = time.perf_counter()
    reference = _REFERENCES.get(reference_path)
    if reference is None:
        if len(_REFERENCES) > 8:
            _REFERENCES.clear()
            _SHOWN.clear()
        reference = _REFERENCES[reference_path] = np.load(reference_path)
    key = (reference_path, display)
    if key not in _SHOWN:
        _SHOWN[key] = _shown(reference, display)
    per_view, m = _evaluate(image, reference, display, ppd, eps, names, which, maps, _SHOWN[key], eccentricity)
    return per_view, m, time.perf_counter() - t0
