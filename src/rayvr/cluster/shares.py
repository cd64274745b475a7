"""How jobs cut their work: shares of frames, views or configurations, and views of a frame
rendered apart from the others.

A share is one call of a worker method (`rayvr.cluster.worker.RenderWorker`) with its keyword
arguments; `work` counts its units (frames, views x frames, configurations) for the progress bar.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..xr.views import ViewSet


@dataclasses.dataclass
class Share:
    """One unit of a job: `method` of a worker called with `kwargs`; `index` orders the results;
    `slot`: the worker number it should run on (None: any; a dead one's go to any other);
    `meta`: the driver's own notes about it (not sent)."""

    index: int
    method: str
    kwargs: dict
    work: int = 1
    slot: int | None = None
    meta: dict = dataclasses.field(default_factory=dict)
    attempts: int = 0


class PinnedViews(ViewSet):
    """Some views of a frame, in the frame's render space: `origin` is the whole frame's, so each
    view's float32 matrices (and so its pixels) are those the whole frame packs."""

    def __init__(self, views, origin, previous: ViewSet | None = None, first_view_index: int = 0):
        super().__init__(list(views), previous)
        self._origin = np.asarray(origin, dtype=np.float64).copy()
        self.first_view_index = int(first_view_index)

    def origin(self) -> np.ndarray:
        return self._origin.copy()


def view_range(view_set: ViewSet, start: int, stop: int, previous: ViewSet | None = None) -> PinnedViews:
    """Views [start, stop) of `view_set`, pinned to its origin."""
    return PinnedViews(view_set.views[start:stop], view_set.origin(), previous,
                       view_set.first_view_index + start)


def split_evenly(total: int, parts: int) -> list[tuple[int, int]]:
    """[start, stop) ranges cutting `total` items into `parts` contiguous pieces whose sizes differ
    by at most one (empty pieces left out)."""
    parts = max(1, min(int(parts), int(total)))
    base, extra = divmod(int(total), parts)
    ranges, start = [], 0
    for i in range(parts):
        stop = start + base + (1 if i < extra else 0)
        ranges.append((start, stop))
        start = stop
    return [r for r in ranges if r[1] > r[0]]


def split_by_weights(total: int, weights) -> list[int]:
    """Integer counts summing to `total`, proportional to `weights` (largest remainders), each at
    least 1 while there are as many items as weights."""
    w = np.maximum(np.asarray(weights, dtype=np.float64), 0.0)
    if len(w) == 0:
        return []
    if not w.sum() > 0:
        w = np.ones(len(w))
    ideal = w / w.sum() * total
    counts = np.floor(ideal).astype(int)
    for i in np.argsort(-(ideal - counts), kind="stable")[: total - counts.sum()]:
        counts[i] += 1
    while total >= len(w) and counts.min() == 0:   # nobody idles: take from the largest share
        counts[int(np.argmin(counts))] += 1
        counts[int(np.argmax(counts))] -= 1
    return [int(c) for c in counts]
