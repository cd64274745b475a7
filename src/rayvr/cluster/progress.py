"""Progress of a job over all its workers: one counter actor, one bar on the driver.

Workers add what they finished under their share's key (`RenderWorker._tick`, at most every
0.2 s); a share that is re-run after its worker died has its key reset, so its work is not
counted twice. The driver polls the job's total and moves one tqdm bar.
"""
from __future__ import annotations


class ProgressCounter:
    """Units done per (job, share) key; run as a Ray actor (rayvr.cluster.pool)."""

    def __init__(self):
        self._counts: dict = {}

    def add(self, key, n: int) -> None:
        self._counts[key] = self._counts.get(key, 0) + int(n)

    def reset(self, key) -> None:
        self._counts.pop(key, None)

    def total(self, job) -> int:
        return sum(v for (j, _), v in self._counts.items() if j == job)

    def clear(self, job) -> None:
        for key in [k for k in self._counts if k[0] == job]:
            del self._counts[key]


class JobBar:
    """One tqdm bar for a job; `show(done)` moves it to `done` units (it may go back after a
    re-run). Disabled: does nothing."""

    def __init__(self, desc: str, total: int, unit: str, enabled: bool):
        from tqdm import tqdm

        self._bar = tqdm(total=total, desc=desc, unit=unit, disable=not enabled, leave=False, dynamic_ncols=True)

    def show(self, done: int) -> None:
        done = min(int(done), self._bar.total or done)
        if done != self._bar.n:
            self._bar.update(done - self._bar.n)
            if done == self._bar.total:
                self._bar.refresh()   # tqdm skips updates within mininterval: show the finished count

    def close(self) -> None:
        self._bar.close()
