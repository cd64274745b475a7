"""What the error-study benchmarks share: options whose defaults differ between a full run and
--quick, and the table's "mean ± std" cells."""
from __future__ import annotations


def add_figure_options(parser, figures: dict) -> None:
    """One option per `figures` entry {name: (full run, --quick)}; given on the command line, it wins."""
    for name, (full, quick) in figures.items():
        parser.add_argument("--" + name.replace("_", "-"), type=type(full), help=f"default {full} (quick: {quick})")


def resolve_figures(args, figures: dict) -> dict:
    """{name: value}: the option as given, else the full run's or --quick's default."""
    return {name: getattr(args, name) if getattr(args, name) is not None else pair[1 if args.quick else 0]
            for name, pair in figures.items()}


def stat_cell(stat) -> str:
    """'mean ± std' of a metric's {"mean", "std"}, or '-'."""
    if not stat:
        return "-"
    return f"{stat['mean']:.4g} ± {stat['std']:.2g}"
