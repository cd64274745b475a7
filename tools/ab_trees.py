#!/usr/bin/env python3
"""Other commits checked out beside this one, for A/B runs (tools/pt_variants.py, tools/gpu_ab.py).

    python3 tools/ab_trees.py COMMIT [NAME]     # .ab/NAME: a git worktree at COMMIT (NAME: its short hash)
    python3 tools/ab_trees.py --src COMMIT [NAME]   # .ab/NAME holding COMMIT's src/ alone (~2 MB)
    python3 tools/ab_trees.py --list
    python3 tools/ab_trees.py --remove NAME

Each tree is a detached `git worktree` under .ab/ (ignored by git), so it shares this clone's
objects and needs no copy of the history. Run it here, before a device call, and carry `.ab`
with the call (a nested checkout travels only when carry names it): then
`python3 tools/pt_variants.py OUT.jsonl NAME:base base` or `python3 tools/gpu_ab.py --base .ab/NAME ...`.
A whole worktree is ~8 MB, so a bisect over many commits takes `--src` trees (what pt_variants
needs: the commit's src/, from `git archive`), a dozen of which fit a call's 64 MiB.
"""
from __future__ import annotations

import argparse
import io
import shutil
import subprocess
import tarfile
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
AB = ROOT / ".ab"


def git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(ROOT), *args], check=True, capture_output=True, text=True).stdout.strip()


def _fresh(commit: str, name: str | None) -> tuple[str, Path]:
    """(the full hash of `commit`, .ab/NAME with any tree of that name removed)."""
    full = git("rev-parse", "--verify", f"{commit}^{{commit}}")
    name = name or git("rev-parse", "--short", full)
    if (AB / name).exists():
        remove(name)
    return full, AB / name


def add(commit: str, name: str | None) -> Path:
    """A detached worktree of `commit` at .ab/NAME (replacing one of that name)."""
    full, path = _fresh(commit, name)
    AB.mkdir(exist_ok=True)
    git("worktree", "add", "--detach", str(path), full)
    return path


def add_src(commit: str, name: str | None) -> Path:
    """`commit`'s src/ alone at .ab/NAME/src (replacing a tree of that name): no worktree."""
    full, path = _fresh(commit, name)
    path.mkdir(parents=True)
    data = subprocess.run(["git", "-C", str(ROOT), "archive", full, "src"], check=True, capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        tar.extractall(path, filter="data")
    return path


def remove(name: str) -> None:
    path = AB / name
    if not path.exists():
        raise SystemExit(f"no tree .ab/{name}")
    if (path / ".git").exists():
        git("worktree", "remove", "--force", str(path))
    else:   # a --src tree
        shutil.rmtree(path)


def listed() -> list[str]:
    """'NAME COMMIT' of each tree under .ab/."""
    out = []
    for block in git("worktree", "list", "--porcelain").split("\n\n"):
        fields = dict(line.split(" ", 1) for line in block.splitlines() if " " in line)
        path = Path(fields.get("worktree", ""))
        if path.parent == AB:
            out.append(f"{path.name} {fields.get('HEAD', '?')[:10]}")
    if AB.is_dir():
        out += [f"{d.name} (src only)" for d in sorted(AB.iterdir()) if (d / "src" / "rayvr").is_dir()
                and not (d / ".git").exists()]
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("commit", nargs="?", help="the commit (any git revision)")
    p.add_argument("name", nargs="?", help="the tree's folder under .ab/ (default: the commit's short hash)")
    p.add_argument("--src", action="store_true", help="the commit's src/ alone, not a worktree")
    p.add_argument("--list", action="store_true")
    p.add_argument("--remove", metavar="NAME")
    args = p.parse_args(argv)
    if args.list:
        print("\n".join(listed()) or "(no trees)")
    elif args.remove:
        remove(args.remove)
    elif args.commit:
        print((add_src if args.src else add)(args.commit, args.name))
    else:
        p.error("name a commit, --list or --remove NAME")
    return 0


if __name__ == "__main__":
    sys.exit(main())
