"""Where the error study's steps run.

`rv.study.measure` and the tuner (`rayvr.tune.tuner.tuned_study`) hand their steps to a runner:
the references (`reference`: cached or rendered), the configurations' rows (`rows`) and the
progressive curves (`curves`). `LocalRunner` runs them in this process on one GPU (the tuner's
cost-model probe then runs here too); `rayvr.cluster.StudyRunner` has the same methods, and
`probe` for the tuner, and runs them on Ray workers (references split by samples, each
configuration and curve on one worker), with the same seeds and the same cache, so that both give
the same study.
"""
from __future__ import annotations

from .metrics import DEFAULT_EPS


class LocalRunner:
    """Every step in this process, on `gpu` (the study's context)."""

    shows_progress = False      # the study's own progress bar covers every step

    def __init__(self, before_wait=None):
        # called once, after the rows are rendered and before waiting for their judgements: GPU
        # work to overlap with the metric pool's (e.g. the next scene's references)
        self.before_wait = before_wait

    def reference(self, scene, view_set, settings, cache_dir=None, sample: int = 0, eps: float = DEFAULT_EPS,
                  gpu=None, tick=None, progress=None):
        """rayvr.study.reference.cached_reference: from the cache, else rendered and stored; then
        rendered on until converged or capped (`progress`: a ReferenceProgress for the extensions)."""
        from .reference import cached_reference

        return cached_reference(scene, view_set, settings, cache_dir, gpu, tick, sample=sample, eps=eps,
                                progress=progress)

    def rows(self, study, configs, reference, motion_references: dict) -> list:
        """One Row per configuration, in order (rayvr.study.measure.Study.row): each configuration
        renders while the metric pool judges the ones before (rayvr.study.pool)."""
        finish, rows = [], {}
        for c in configs:
            finish.append(study.row_later(c, reference, motion_references))
            for k, f in enumerate(finish):   # rows judged by now are finished (and cached) at once
                if k not in rows and f.ready():
                    rows[k] = f()
        if self.before_wait is not None:
            before_wait, self.before_wait = self.before_wait, None
            with study.progress.step("wait", 0.0, "other GPU work while the images are judged"):
                before_wait()
        return [rows[k] if k in rows else f() for k, f in enumerate(finish)]

    def curves(self, study, reference) -> list:
        """The progressive curves (rayvr.study.measure.Study.curve), in order, rendered while the
        metric pool judges."""
        finish = [study.curve_later(name, options, reference) for name, options in study.curve_graphs()]
        return [f() for f in finish]
