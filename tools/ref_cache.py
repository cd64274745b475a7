#!/usr/bin/env python3
"""Carry the error study's reference cache between device calls (a machine's /tmp is gone once it
is given back, and a file that comes back from a call must stay under 16 MiB).

    python3 tools/ref_cache.py split CACHE_DIR OUT_DIR    # each .npz as NAME.npz.partNN, <= 15 MB
    python3 tools/ref_cache.py join PARTS_DIR CACHE_DIR   # the parts back into whole .npz files

tools/gpu-bench's `reference` mode splits the cache into $OUT after rendering and joins a carried
`.refcache/` (the parts a call brought back, copied there) before it: the reference then resumes
where the last call stopped, under the time cap summed over its runs.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

PART_BYTES = 15_000_000


def split(cache: Path, out: Path) -> list[Path]:
    """Every .npz in `cache` as parts of at most PART_BYTES in `out`."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for f in sorted(cache.glob("*.npz")):
        data = f.read_bytes()
        for i in range(0, max(len(data), 1), PART_BYTES):
            part = out / f"{f.name}.part{i // PART_BYTES:02d}"
            part.write_bytes(data[i:i + PART_BYTES])
            written.append(part)
    return written


def join(parts: Path, cache: Path) -> list[Path]:
    """The .npz files whose parts are in `parts`, whole, in `cache`."""
    cache.mkdir(parents=True, exist_ok=True)
    names = sorted({p.name.rsplit(".part", 1)[0] for p in parts.glob("*.npz.part*")})
    joined = []
    for name in names:
        pieces = sorted(parts.glob(f"{name}.part*"), key=lambda p: int(p.name.rsplit(".part", 1)[1]))
        (cache / name).write_bytes(b"".join(p.read_bytes() for p in pieces))
        joined.append(cache / name)
    return joined


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("verb", choices=("split", "join"))
    p.add_argument("src", type=Path)
    p.add_argument("dst", type=Path)
    args = p.parse_args(argv)
    done = split(args.src, args.dst) if args.verb == "split" else join(args.src, args.dst)
    print(f"{args.verb}: {len(done)} file(s) in {args.dst}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
