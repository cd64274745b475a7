"""What the error study found: the reference, one row per configuration, progressive curves.

`Results.as_dict()` is results.json (docs/CONTRACTS.md): {"reference": {...}, "rows": [...],
"progressive": [...], "study": {...}} and, after `rayvr tune`, "tuned". Each row: `name`,
`gpu_ms`, every metric as {"mean", "std", "n"} over the judged frames and views, `frames`, `views`,
`size`, `settings`, and `motion` (the same metrics along the trajectory), `floor` (the
configuration's converged image against the reference) and `timed_on` (the cluster worker that
measured it; None in one process).
"""
from __future__ import annotations

import dataclasses
import json
import math

import numpy as np

from .metrics import LOWER_IS_BETTER, METRICS


def summarize(samples: dict) -> dict:
    """{metric: [per-view arrays, one per judged frame]} -> {metric: {"mean", "std", "per_view", "n"}}:
    mean and sample standard deviation over every (frame, view) value, the mean per view, and
    how many values there were (frames x views)."""
    out = {}
    for metric, frames in samples.items():
        a = np.asarray(frames, dtype=np.float64)           # (frames, views)
        flat = a.ravel()
        mean = float(flat.mean())          # inf when a PSNR is (identical images)
        std = float(flat.std(ddof=1)) if flat.size > 1 else 0.0
        if not np.isfinite(flat).all():
            std = float("nan")
        out[metric] = {"mean": mean, "std": std, "per_view": [float(v) for v in a.mean(axis=0)], "n": int(flat.size)}
    return out


@dataclasses.dataclass
class Row:
    """One measured configuration."""

    name: str
    settings: dict
    gpu_ms: float                 # GPU ms per frame (sum of the per-pass means)
    pass_ms: dict                 # pass -> GPU ms per frame
    cpu_ms: float                 # CPU ms inside the graph's execute() per frame
    frames: int                   # frames judged (static view)
    views: int
    size: tuple
    errors: dict                  # metric -> {"mean", "std", "per_view"}
    motion: dict | None = None    # {"frames", "sampled_frames", metric -> {...}}
    floor: dict | None = None     # see rayvr.study.floor.Floor.against, plus its metrics
    tuned: bool = False
    negative_values: int = 0      # negative radiance values judged as 0 (as the tone mapper shows them)
    timed_on: str | None = None   # the worker (label, GPU, renderer, host) that measured it on a cluster
    image: object = None          # the first judged frame (views, h, w, 4), for the report
    maps: dict = dataclasses.field(default_factory=dict)   # its per-pixel error maps
    floor_image: object = None
    motion_image: object = None

    def mean(self, metric: str) -> float:
        return self.errors[metric]["mean"]

    def as_dict(self) -> dict:
        d = {"name": self.name, "gpu_ms": self.gpu_ms, "pass_ms": dict(self.pass_ms), "cpu_ms": self.cpu_ms}
        d.update({m: {"mean": v["mean"], "std": v["std"], "n": v.get("n")} for m, v in self.errors.items()})
        d["per_view"] = {m: v["per_view"] for m, v in self.errors.items()}
        d.update({"frames": self.frames, "views": self.views, "size": list(self.size), "settings": self.settings,
                  "motion": self.motion, "floor": self.floor, "tuned": self.tuned,
                  "negative_values": self.negative_values, "timed_on": self.timed_on})
        return d


@dataclasses.dataclass
class Curve:
    """Error against accumulated time of one progressive render (raw, or with a denoiser)."""

    name: str
    settings: dict
    gpu_ms_per_frame: float
    points: list                  # {"frames", "wall_s", "gpu_s", metric: value, ...}
    timed_on: str | None = None   # the cluster worker that rendered it (None in one process)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def effects_text(effects: dict) -> str:
    """The most common effect, then the materials that differ: 'SHADOWS, Floor=REFLECTIONS'."""
    if not effects:
        return "-"
    values = list(effects.values())
    common = max(set(values), key=values.count)
    return ", ".join([common] + [f"{m}={e}" for m, e in effects.items() if e != common])


def markdown_table(cols: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(str(c).replace("|", "/") for c in row) + " |" for row in rows]
    return "\n".join(lines)


def fmt(value, digits: int = 4) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        if math.isinf(value):
            return "inf"
        if math.isnan(value):
            return "nan"
        return f"{value:.{digits}g}"
    return str(value)


def fmt_stat(stat: dict | None) -> str:
    """'mean ± std' of a summarized metric."""
    if not stat:
        return "-"
    return f"{fmt(stat['mean'], 3)} ± {fmt(stat['std'], 2)}"


class Results:
    """The reference (rayvr.study.reference.Reference), the rows, the curves and the study's
    context (scene, views, size, display, ppd, eps, timing method, what was chosen and why)."""

    def __init__(self, reference, rows: list[Row], curves: list[Curve], study: dict, motion_references=()):
        self.reference = reference
        self.rows = list(rows)
        self.curves = list(curves)
        self.study = dict(study)
        self.motion_references = list(motion_references)
        self.tuned = None             # rayvr tune adds its TuneResult

    def __getitem__(self, name: str) -> Row:
        for row in self.rows:
            if row.name == name:
                return row
        raise KeyError(f"no configuration '{name}'; have {', '.join(r.name for r in self.rows)}")

    @property
    def method(self) -> str:
        """How GPU time was measured (the graph profile's method)."""
        return self.study.get("timing", "?")

    def metrics(self) -> list[str]:
        """The metrics the rows have, in METRICS' order."""
        return [m for m in METRICS if any(m in r.errors for r in self.rows)]

    def pareto(self, metric: str = "flip") -> list[Row]:
        """The rows no other one beats in both GPU ms and `metric`'s mean, fastest first."""
        sign = 1.0 if LOWER_IS_BETTER[metric] else -1.0
        front, best = [], math.inf
        for row in sorted(self.rows, key=lambda r: (r.gpu_ms, sign * r.mean(metric))):
            if sign * row.mean(metric) < best:
                front.append(row)
                best = sign * row.mean(metric)
        return front

    # -- text --------------------------------------------------------------------------------
    def table_data(self) -> tuple[list[str], list[list[str]]]:
        """(columns, cells): configuration, GPU ms, each metric as mean ± std over the judged
        frames and views, FLIP in motion, the floor's relMSE and how much of it is bias, and the
        worker that timed it when a cluster did."""
        metrics = self.metrics()
        timed_on = any(r.timed_on for r in self.rows)
        cols = ["configuration", "GPU ms", *(METRICS[m] for m in metrics), "FLIP in motion", "floor relMSE",
                "floor bias", *(["timed on"] if timed_on else [])]
        rows = []
        for r in self.rows:
            floor = r.floor or {}
            bias = "-" if not floor else ("within noise" if floor["within_noise"] else fmt(floor["bias_relmse"], 3))
            rows.append([r.name, fmt(r.gpu_ms, 4), *(fmt_stat(r.errors.get(m)) for m in metrics),
                         fmt_stat((r.motion or {}).get("flip")), fmt(floor.get("relmse"), 3), bias,
                         *([fmt(r.timed_on)] if timed_on else [])])
        return cols, rows

    def settings_data(self) -> tuple[list[str], list[list[str]]]:
        """(columns, cells): every row's settings, stated."""
        keys = ["graph", "spp", "bounces", "reflection_bounces", "light_samples", "frames_accumulated", "denoiser",
                "gi", "direct"]
        rows = []
        for r in self.rows:
            rows.append([r.name, *(fmt(r.settings.get(k)) for k in keys), effects_text(r.settings.get("effects", {}))])
        return ["configuration", *[k.replace("bounces", "path bounces") if k == "bounces" else k for k in keys],
                "effects"], rows

    def curve_data(self) -> tuple[list[str], list[list[str]]]:
        """(columns, cells): each progressive curve's points."""
        metrics = [m for m in self.metrics() if any(m in p for c in self.curves for p in c.points)]
        cols = ["render", "frames", "wall s", "GPU s", *(METRICS[m] for m in metrics)]
        rows = [[c.name, str(p["frames"]), fmt(p["wall_s"], 3), fmt(p["gpu_s"], 3), *(fmt(p[m], 4) for m in metrics)]
                for c in self.curves for p in c.points]
        return cols, rows

    def table_title(self) -> str:
        """The table's title: the scene and whether the reference it is judged against converged."""
        ref = self.reference
        scene = self.study.get("scene", "?")
        if ref is None:
            return f"Error against GPU time: {scene}"
        if ref.halves_identical or ref.converged:
            return f"Error against GPU time: {scene}, against a converged reference ({ref.samples_per_pixel} spp)"
        return (f"Error against GPU time: {scene}, against a reference that has NOT converged (halves predict relMSE "
                f"{ref.noise_relmse:.2e} > {ref.settings.tolerance:.0e}): errors near its own noise do not tell "
                f"configurations apart")

    def table(self) -> str:
        """The results table as markdown."""
        return markdown_table(*self.table_data())

    def __str__(self) -> str:
        return self.table()

    def as_dict(self) -> dict:
        ref = self.reference.as_dict() if self.reference is not None else {}
        ref["trajectory_references"] = [
            {"frame": frame, **{k: r.as_dict()[k] for k in ("convergence", "bounces", "seeds", "source")}}
            for frame, r in self.motion_references]
        doc = {"reference": ref, "rows": [r.as_dict() for r in self.rows],
               "progressive": [c.as_dict() for c in self.curves], "study": self.study}
        if self.tuned is not None:
            doc["tuned"] = self.tuned.as_dict()
        return doc

    def to_json(self) -> str:
        return json.dumps(_json_safe(self.as_dict()), indent=2, default=str) + "\n"


def _json_safe(value):
    """inf/nan as strings ("inf", "nan"): results.json stays strict JSON."""
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else ("-inf" if value < 0 else "nan")
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value
