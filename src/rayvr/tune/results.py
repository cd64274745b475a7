"""Results of `rayvr.tune.measure`: one row per configuration (GPU ms per frame, per pass, image
error), as a markdown table, CSV, JSON and error-vs-ms plots (matplotlib, Agg: no display)."""
from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path

from ..fileio import atomic_write, write_text
from .metrics import LOWER_IS_BETTER, METRICS


@dataclasses.dataclass
class ConfigResult:
    """One measured configuration."""

    name: str
    effects: dict          # material name -> effect name
    options: dict
    frame_ms: float        # GPU ms per frame (sum of the per-pass means)
    pass_ms: dict          # pass -> GPU ms per frame
    cpu_ms: float          # CPU ms inside the graph's execute() per frame
    errors: dict           # metric -> value (see rayvr.tune.metrics.METRICS)
    image: object = None   # the linear image (views, h, w, c) when measure(keep_images=True)
    timed_on: str | None = None   # the worker (GPU, host) that timed it, when a cluster measured it

    def as_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d.pop("image")
        return d


def _fmt(value) -> str:
    if isinstance(value, float):
        return "inf" if math.isinf(value) else f"{value:.4g}"
    return str(value)


class Results:
    """`rows` (ConfigResult per configuration) and `info` (scene, views, size, frames, timing
    method, reference)."""

    def __init__(self, rows: list[ConfigResult], info: dict):
        self.rows = list(rows)
        self.info = dict(info)

    @classmethod
    def load(cls, path) -> Results:
        """Results from a results.json that `write()` made (images are not stored)."""
        from ..errors import OptionError

        try:
            doc = json.loads(Path(path).read_text())
            rows = [ConfigResult(**c) for c in doc["configurations"]]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise OptionError(f"{path}: not a rayvr.tune results.json ({exc})") from None
        return cls(rows, doc.get("info", {}))

    @property
    def method(self) -> str:
        """How the GPU time was measured (the graph profile's method)."""
        return self.info.get("method", "?")

    def __getitem__(self, name: str) -> ConfigResult:
        for row in self.rows:
            if row.name == name:
                return row
        raise KeyError(f"no configuration '{name}'; have {', '.join(r.name for r in self.rows)}")

    def metrics(self) -> list[str]:
        """The metrics any row has, in METRICS' order."""
        return [m for m in METRICS if any(m in r.errors for r in self.rows)]

    def passes(self) -> list[str]:
        """Every pass any row timed, in first-seen order."""
        names = []
        for row in self.rows:
            names += [p for p in row.pass_ms if p not in names]
        return names

    def pareto(self, metric: str = "flip") -> list[ConfigResult]:
        """The configurations no other one beats in both ms and `metric`, fastest first."""
        sign = 1.0 if LOWER_IS_BETTER[metric] else -1.0
        front, best = [], math.inf
        for row in sorted(self.rows, key=lambda r: (r.frame_ms, sign * r.errors[metric])):
            if sign * row.errors[metric] < best:
                front.append(row)
                best = sign * row.errors[metric]
        return front

    # -- text --------------------------------------------------------------------------------
    def table(self, per_pass: bool = False) -> str:
        """A markdown table: configuration, GPU ms per frame, each metric (and each pass's ms)."""
        passes = self.passes() if per_pass else []
        timed_on = any(r.timed_on for r in self.rows)
        cols = ["configuration", "GPU ms/frame", *(METRICS[m] for m in self.metrics()), *(f"{p} ms" for p in passes),
                *(["timed on"] if timed_on else [])]
        lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
        for r in self.rows:
            cells = [r.name, _fmt(r.frame_ms), *(_fmt(r.errors[m]) for m in self.metrics()),
                     *(_fmt(r.pass_ms[p]) if p in r.pass_ms else "-" for p in passes),
                     *([r.timed_on or "-"] if timed_on else [])]
            lines.append("| " + " | ".join(c.replace("|", "/") for c in cells) + " |")
        i = self.info
        lines.append("")
        lines.append(f"{i.get('scene')}: {i.get('views')} view(s) of {i.get('size', ['?', '?'])[0]}x"
                     f"{i.get('size', ['?', '?'])[1]}, {i.get('frames')} timed frames after {i.get('warmup')} "
                     f"warm-up; timing: {self.method}; reference: {i.get('reference')}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()

    def as_dict(self) -> dict:
        return {"info": self.info, "configurations": [r.as_dict() for r in self.rows]}

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2, default=str,
                          allow_nan=True) + "\n"

    def to_csv(self) -> str:
        passes, metrics = self.passes(), self.metrics()
        timed_on = any(r.timed_on for r in self.rows)
        out = io.StringIO()
        w = csv.writer(out)
        w.writerow(["configuration", "frame_ms", *metrics, *(f"{p}_ms" for p in passes), "method",
                    *(["timed_on"] if timed_on else [])])
        for r in self.rows:
            w.writerow([r.name, r.frame_ms, *(r.errors[m] for m in metrics),
                        *(r.pass_ms.get(p, "") for p in passes), self.method, *([r.timed_on or ""] if timed_on else [])])
        return out.getvalue()

    # -- plots -------------------------------------------------------------------------------
    def plot(self, metric: str, path, budget_ms: float | None = None) -> Path:
        """Error (`metric`) against GPU ms per frame, one labelled point per configuration and
        the Pareto front as a line; a vertical line at `budget_ms`. Written atomically (PNG)."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        if metric not in self.metrics():
            raise KeyError(f"no metric '{metric}' in these results; have {', '.join(self.metrics())}")
        fig = Figure(figsize=(6.4, 4.4), dpi=110)
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        xs = [r.frame_ms for r in self.rows]
        ys = [r.errors[metric] for r in self.rows]
        ax.scatter(xs, ys, zorder=3)
        for i, (r, x, y) in enumerate(zip(self.rows, xs, ys)):
            # Staggered offsets keep the labels of nearby points apart.
            ax.annotate(r.name, (x, y), textcoords="offset points", xytext=(5, 4 - 10 * (i % 3)), fontsize=7)
        front = self.pareto(metric)
        ax.plot([r.frame_ms for r in front], [r.errors[metric] for r in front], "--", lw=1, color="gray",
                label="Pareto front", zorder=2)
        if budget_ms:
            ax.axvline(budget_ms, color="red", lw=1, label=f"budget {budget_ms:g} ms")
        if min(xs) > 0 and max(xs) > 20 * min(xs):
            ax.set_xscale("log")
        if metric == "relmse" and all(y > 0 for y in ys):
            ax.set_yscale("log")
        ax.set_xlabel(f"GPU ms per frame ({self.method})")
        ax.set_ylabel(METRICS[metric] + ("  (lower is better)" if LOWER_IS_BETTER[metric] else "  (higher is better)"))
        i = self.info
        ax.set_title(f"{i.get('scene')}: {i.get('views')} x {i.get('size', ['?'])[0]}x{i.get('size', ['?', '?'])[1]}",
                     fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        return atomic_write(Path(path), lambda tmp: fig.savefig(tmp, format="png"))

    def write(self, folder, budget_ms: float | None = None, stem: str = "error_vs_ms") -> list[Path]:
        """table.md, results.csv, results.json and one `{stem}_{metric}.png` per metric in
        `folder`, each written atomically. Returns the paths."""
        folder = Path(folder)
        paths = [write_text(folder / "table.md", self.table(per_pass=True) + "\n"),
                 write_text(folder / "results.csv", self.to_csv()),
                 write_text(folder / "results.json", self.to_json())]
        paths += [self.plot(m, folder / f"{stem}_{m}.png", budget_ms) for m in self.metrics()]
        return paths
