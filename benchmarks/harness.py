"""The benchmark harness: `python -m benchmarks NAME [--quick] [--out DIR] [options]`.

A benchmark is a module `benchmarks/NAME.py` (names starting with '_' are helpers) with
`run(args) -> {"columns": [...], "rows": [[...] or {...}, ...], "notes": [...] (optional)}` and
optionally `add_arguments(parser)`. The harness adds device (GL_RENDERER), driver (GL_VERSION),
UTC date and commit, writes `OUT/NAME.json` (the latest run) and appends the rows to `OUT/NAME.md`.
Runs on a software rasteriser (llvmpipe) are labelled 'software' in both files.
"""
from __future__ import annotations

import argparse
import datetime
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

from rayvr.fileio import atomic_group, write_text

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def available() -> list[str]:
    """Benchmark names: the modules of this package that are not helpers."""
    skip = {"harness", "__main__", "__init__"}
    return sorted(p.stem for p in HERE.glob("*.py") if p.stem not in skip and not p.stem.startswith("_"))


def commit() -> str:
    """HEAD's short hash; RAYVR_COMMIT names it where the tree has no git (the GPU machine's copy)."""
    if os.environ.get("RAYVR_COMMIT"):
        return os.environ["RAYVR_COMMIT"]
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True,
                             text=True, timeout=10)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def environment(gpu) -> dict:
    """Device, driver, date and commit of this run."""
    caps = gpu.caps
    return {
        "device": caps.renderer,
        "driver": caps.version,
        "software": bool(caps.is_software),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "commit": commit(),
    }


def _rows_as_lists(result: dict) -> list[list]:
    cols = result["columns"]
    return [[row.get(c, "") for c in cols] if isinstance(row, dict) else list(row) for row in result["rows"]]


def _cell(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v).replace("|", "/")


def record(name: str, result: dict, env: dict, options: dict, out: Path) -> tuple[Path, Path]:
    """Write OUT/NAME.json and append to OUT/NAME.md (both replaced together, atomically);
    returns both paths."""
    rows = _rows_as_lists(result)
    doc = {"benchmark": name, **env, "options": options, "columns": result["columns"], "rows": rows,
           "notes": result.get("notes", [])}
    jpath, mpath = out / f"{name}.json", out / f"{name}.md"
    cols = ["date", "commit", "device", "driver"] + list(result["columns"])
    header = "| " + " | ".join(cols) + " |"
    lines = []
    if not mpath.exists():
        lines += [f"# benchmark: {name}"]
    if _last_header(mpath) != header:   # a new file, or columns changed: a new table
        lines += ["", header, "|" + "---|" * len(cols)]
    device = env["device"] + (" (software)" if env["software"] else "")
    quick = " (quick)" if options.get("quick") else ""
    for row in rows:
        cells = [env["date"], env["commit"] + quick, device, env["driver"], *map(_cell, row)]
        lines.append("| " + " | ".join(cells) + " |")
    old = mpath.read_text() if mpath.exists() else ""
    with atomic_group():
        write_text(jpath, json.dumps(doc, indent=2, default=str) + "\n")
        write_text(mpath, old + "\n".join(lines) + "\n")
    return jpath, mpath


def _last_header(mpath: Path) -> str | None:
    """The header row of the last table in a results markdown file (None without one)."""
    if not mpath.exists():
        return None
    heads = [line.rstrip("\n") for line in mpath.read_text().splitlines() if line.startswith("| date |")]
    return heads[-1] if heads else None


def print_table(result: dict) -> None:
    cols = [str(c) for c in result["columns"]]
    rows = [[_cell(v) for v in r] for r in _rows_as_lists(result)]
    widths = [max(len(c), *(len(r[i]) for r in rows)) if rows else len(c) for i, c in enumerate(cols)]
    print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
    for r in rows:
        print("  ".join(v.rjust(w) for v, w in zip(r, widths)))
    for note in result.get("notes", []):
        print(f"note: {note}")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    names = available()
    first = argparse.ArgumentParser(add_help=False)
    first.add_argument("name", nargs="?")
    known, _ = first.parse_known_args(argv)
    parser = argparse.ArgumentParser(prog="python -m benchmarks",
                                     description=f"Run a benchmark. Available: {', '.join(names)}")
    parser.add_argument("name", help="benchmark to run", choices=names, metavar="NAME")
    parser.add_argument("--quick", action="store_true", help="a small smoke run (e.g. on llvmpipe)")
    parser.add_argument("--out", type=Path, default=RESULTS, help=f"results folder (default {RESULTS})")
    parser.add_argument("--no-save", action="store_true", help="print only, write no result files")
    module = None
    if known.name in names:
        module = importlib.import_module(f"benchmarks.{known.name}")
        if hasattr(module, "add_arguments"):
            module.add_arguments(parser)
    elif known.name and not known.name.startswith("-"):
        from rayvr.errors import did_you_mean
        print(f"python -m benchmarks: unknown benchmark {known.name!r}{did_you_mean(known.name, names)}; "
              f"available: {', '.join(names)}", file=sys.stderr)
        return 2
    args = parser.parse_args(argv)

    from rayvr.errors import RayvrError
    from rayvr.gpu import get_context

    try:
        env = environment(get_context())
        result = module.run(args)
    except RayvrError as exc:
        print(f"python -m benchmarks {args.name}: error: {exc}", file=sys.stderr)
        return 2
    print(f"{args.name} on {env['device']} ({env['driver']}), commit {env['commit']}")
    print_table(result)
    if not args.no_save:
        options = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()
                   if k not in ("name", "out", "no_save")}
        for path in record(args.name, result, env, options, args.out):
            print(f"wrote {path}")
    return 0
