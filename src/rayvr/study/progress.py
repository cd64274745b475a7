"""One progress bar over a whole error study, with an ETA from what each step is expected to cost.

Steps differ by orders of magnitude (a converged reference against one configuration frame) and
by kind (rendering is GPU work, metrics are CPU work, whose ratio differs between llvmpipe and a
GPU), so a plain step counter would lie. Every step is planned up front with its kind and its
cost in units of that kind (paths traced, pixels judged, renderers built). As steps finish, the
seconds per unit of each kind are learned from the steps themselves; a kind not seen yet is
assumed to cost like the others in proportion to PRIOR. The bar counts seconds: done = the seconds
spent, total = those plus the remaining steps' units at the learned rates, so tqdm's
"remaining" is that estimate.

A kind can run concurrently with the rest (`concurrent(kind, workers)`: the error metrics in
rayvr.study.pool's worker processes). Its steps are not timed here: each reports the seconds its
worker spent (`finished(kind, units, seconds)`), which teach its rate, and its remaining units
take rate x units / workers of wall time, overlapped with the other kinds: the remaining time
is the larger of the two. The time this process waits for it is a step of kind "wait" (counted
as spent, never planned).

With RAYVR_STUDY_LOG set (e.g. to "-": stderr, or a file path) every step and every concurrent
step's report is also logged as one line, with the seconds since the study began: where a long
study's time goes, readable from a log that a timeout cut short.
"""
from __future__ import annotations

import contextlib
import os
import sys
import time

# Relative seconds per unit before any step of the kind was timed (llvmpipe's ratios).
PRIOR = {"render": 2.5e-6, "metric": 2.5e-6, "setup": 0.4}
# A GPU renders a unit this much faster, relative to a CPU core's metrics, than llvmpipe (a
# datacenter GPU's Cornell study at 2x1440x1600: 2.8e-9 s a unit for the reference, 1.3e-6 for a
# judged image's metrics, on one core each; without it the first ETA, learned from a judgement,
# was 180x the study's length).
HARDWARE_RENDER_SCALE = 2e-3


class StudyProgress:
    """Planned steps and their progress; `step(kind, units)` wraps one as it runs."""

    def __init__(self, enabled: bool = True, desc: str = "error study", hardware: bool = False):
        self.enabled = enabled
        self.prior = dict(PRIOR)
        if hardware:   # rendering on a GPU, not on the CPU cores (llvmpipe) that judge the images
            self.prior["render"] *= HARDWARE_RENDER_SCALE
        self.desc = desc
        self.planned: dict[str, float] = {}     # kind -> units still to do
        self.done_units: dict[str, float] = {}
        self.done_s: dict[str, float] = {}
        self.spent = 0.0
        self.bar = None
        self._partial = 0.0                      # seconds into the current step
        self._shown = 0.0
        self.workers: dict[str, int] = {}        # concurrent kind -> its workers
        self._t0 = time.perf_counter()
        self._log_to = os.environ.get("RAYVR_STUDY_LOG")

    def _log(self, text: str) -> None:
        if not self._log_to:
            return
        line = f"[{time.perf_counter() - self._t0:8.1f} s] {self.desc}: {text}\n"
        if self._log_to == "-":
            sys.stderr.write(line)
            sys.stderr.flush()
        else:
            with open(self._log_to, "a") as f:
                f.write(line)

    def plan(self, kind: str, units: float) -> None:
        """Add a step of `units` of `kind` to the plan."""
        self.planned[kind] = self.planned.get(kind, 0.0) + float(units)

    def rate(self, kind: str) -> float:
        """Seconds per unit of `kind`: learned, else the prior scaled like the learned kinds."""
        if self.done_units.get(kind):
            return self.done_s[kind] / self.done_units[kind]
        prior = self.prior
        seen = [k for k in self.done_units if self.done_units[k] and k in prior]
        scale = sum(self.done_s[k] for k in seen) / sum(prior[k] * self.done_units[k] for k in seen) if seen else 1.0
        return prior.get(kind, 1e-6) * scale

    def concurrent(self, kind: str, workers: int) -> None:
        """`kind` runs on `workers` workers beside this process from now on (0: here again)."""
        if workers > 0:
            self.workers[kind] = int(workers)
        else:
            self.workers.pop(kind, None)

    def in_flight(self, kind: str, units: float) -> None:
        """A concurrent step of `units` was handed to a worker (its units stay planned until it finishes)."""
        self._refresh()

    def finished(self, kind: str, units: float, seconds: float) -> None:
        """A concurrent step of `units` finished after `seconds` of its worker's time (unplanned
        work, 0 units, teaches no rate)."""
        self._log(f"{kind} done in a worker: {units:.3g} units, {seconds:.2f} s")
        if not units:
            return
        self.planned[kind] = max(0.0, self.planned.get(kind, 0.0) - units)
        self.done_units[kind] = self.done_units.get(kind, 0.0) + units
        self.done_s[kind] = self.done_s.get(kind, 0.0) + float(seconds)
        self._refresh()

    def remaining_s(self) -> float:
        here = sum(units * self.rate(kind) for kind, units in self.planned.items() if kind not in self.workers)
        beside = sum(units * self.rate(kind) / self.workers[kind] for kind, units in self.planned.items()
                     if kind in self.workers)
        return max(here, beside)

    def _refresh(self, force: bool = False) -> None:
        if self.bar is None:
            return
        now = time.perf_counter()
        if not force and now - self._shown < 0.25:
            return
        self._shown = now
        done = self.spent + self._partial
        # remaining_s still counts the running step in full; its partial seconds are in `done`
        self.bar.total = max(self.spent + self.remaining_s(), done, 1e-9)
        self.bar.n = done
        self.bar.refresh()

    def start(self) -> None:
        from tqdm import tqdm

        if self.enabled:
            self.bar = tqdm(total=max(self.remaining_s(), 1e-9), desc=self.desc, unit="s", leave=False,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed} elapsed, ~{remaining} left "
                                       "{postfix}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def note(self, text: str) -> None:
        """One line of results on stderr, above the bar (and in the log)."""
        if self.bar is not None:
            self.bar.write(text, file=sys.stderr)
        elif self.enabled:
            print(text, file=sys.stderr, flush=True)
        self._log(text)

    @contextlib.contextmanager
    def step(self, kind: str, units: float, label: str = ""):
        """Run one planned step; the block may call the yielded `tick(fraction)` as it goes."""
        t0 = time.perf_counter()
        expected = units * self.rate(kind)
        if self.bar is not None and label:
            self.bar.set_postfix_str(label, refresh=False)

        def tick(fraction: float) -> None:
            self._partial = min(max(fraction, 0.0), 1.0) * expected
            self._refresh()

        try:
            yield tick
        finally:
            took = time.perf_counter() - t0
            if units:
                self.planned[kind] = max(0.0, self.planned.get(kind, 0.0) - units)
                self.done_units[kind] = self.done_units.get(kind, 0.0) + units
                self.done_s[kind] = self.done_s.get(kind, 0.0) + took
            self.spent += took
            self._log(f"{kind} {label or '-'}: {units:.3g} units, {took:.2f} s; ~{self.remaining_s():.0f} s left")
            self._partial = 0.0
            self._refresh(force=True)

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.close()
