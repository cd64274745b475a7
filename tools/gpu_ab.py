#!/usr/bin/env python3
"""A/B of two rayvr trees on the same GPU, interleaved: base, head, base, head, ... so that clock
and thermal drift hit both alike. Each round runs every benchmark once in each tree (no result
files are written); the table gives, per benchmark row and number column, the median of each
side, the relative change and the spread of the rounds (max - min over median), which is the
noise a change must beat.

    python3 tools/ab_trees.py <base> base                                # here, before the run: .ab/base
    python3 tools/gpu_ab.py --base .ab/base --rounds 5 -- rays --scenes .scenes/tauray_test.glb
    python3 tools/gpu_ab.py --base .ab/base --rounds 5 --suite issue10     # rays, hybrid, views, pt

On the device machine, run it after the preamble that ../shared/tools/gpu-prep prints (carry .gl,
.whl, .scenes and .ab).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

SUITES = {
    "issue10": [
        ["rays", "--scenes", ".scenes/tauray_test.glb,.scenes/MetalRoughSpheresNoTextures.glb"],
        ["hybrid", "--scene", ".scenes/tauray_test.glb"],
        ["views_scaling", "--scene", ".scenes/tauray_test.glb", "--views", "1,64"],
        ["path_tracing", "--scene", ".scenes/tauray_test.glb", "--size", "1440x1600"],
    ],
}


ROOT = Path(__file__).resolve().parents[1]


def run_once(tree: Path, bench: list[str], timeout: int) -> dict:
    """One run of this checkout's `python -m benchmarks` with `tree`'s src/ first on PYTHONPATH
    (so a `--src` tree of tools/ab_trees.py serves, and relative scene paths mean the same for both
    sides); the JSON it writes to a scratch folder."""
    with tempfile.TemporaryDirectory() as out:
        env = {**os.environ, "PYTHONPATH": f"{tree / 'src'}:{ROOT}:{os.environ.get('PYTHONPATH', '')}"}
        cmd = [sys.executable, "-m", "benchmarks", *bench[:1], "--out", out, *bench[1:]]
        subprocess.run(cmd, cwd=ROOT, env=env, check=True, timeout=timeout, stdout=subprocess.DEVNULL)
        return json.loads(next(Path(out).glob("*.json")).read_text())


def numbers(result: dict) -> dict[tuple, float]:
    """{(row label, column): value} for the numeric cells; the label is the row's text cells."""
    cols = result["columns"]
    out = {}
    for row in result["rows"]:
        label = " ".join(str(c) for c in row if isinstance(c, str))
        for c, v in zip(cols, row):
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                out[(label, c)] = float(v)
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--base", required=True, type=Path, help="the other tree (a checkout or git archive)")
    p.add_argument("--head", default=Path("."), type=Path, help="this tree (default .)")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--suite", choices=sorted(SUITES))
    p.add_argument("--timeout", type=int, default=300, help="seconds per benchmark run")
    p.add_argument("bench", nargs=argparse.REMAINDER, help="-- NAME [benchmark options]")
    args = p.parse_args()
    benches = SUITES[args.suite] if args.suite else [[a for a in args.bench if a != "--"]]
    for bench in benches:
        runs = {"base": [], "head": []}
        for _ in range(args.rounds):
            for side, tree in (("base", args.base), ("head", args.head)):
                runs[side].append(numbers(run_once(tree.resolve(), bench, args.timeout)))
        print(f"\n== {' '.join(bench)}  ({args.rounds} interleaved rounds)")
        print(f"{'row':<40} {'column':<24} {'base':>10} {'head':>10} {'change':>8} {'spread':>8}")
        for key in runs["head"][0]:
            b = [r[key] for r in runs["base"] if key in r]
            h = [r[key] for r in runs["head"]]
            if not b:
                continue
            mb, mh = statistics.median(b), statistics.median(h)
            spread = max((max(x) - min(x)) / abs(statistics.median(x)) if statistics.median(x) else 0.0 for x in (b, h))
            change = (mh - mb) / abs(mb) if mb else 0.0
            print(f"{key[0][:40]:<40} {key[1][:24]:<24} {mb:10.4g} {mh:10.4g} {100 * change:7.1f}% {100 * spread:7.1f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main())
