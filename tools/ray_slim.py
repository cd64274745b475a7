#!/usr/bin/env python3
"""Builds .whlr/: a slim Ray wheel and the wheels of Ray's runtime dependencies that the lent GPU
machine lacks, small enough to carry there (64 MiB per call for the whole tree; this is ~36 MB).

    python3 tools/ray_slim.py                 # ray 2.60.0 (what CI's `pip install .[cluster]` gets now), cp312
    python3 tools/ray_slim.py --version 2.60.0 --python 3.12 --out .whlr --wheel /tmp/raywhl/ray-...whl

The GPU machine (Python 3.12, x86-64, no network) installs them with tools/gpu-bench (pip install
--no-index --no-deps --target /tmp/site .whl/*.whl .whlr/*.whl); carry [".gl", ".whl", ".whlr", ".scenes"].

What is stripped (none of it is imported by `import ray`, ray.init(include_dashboard=False), the
GCS, raylet, dashboard head (--minimal) and agent, the runtime-env agent, the log monitor and the
autoscaler monitor, nor by rayvr.cluster's actors, put/get/wait/kill and NodeAffinity scheduling;
measured with an import logger in every Ray process over tests/test_cluster*.py on Python 3.12):
  ray/jars (Java workers, 31 MB), ray/dashboard/client/build (the web UI), ray/rllib, ray/data,
  ray/serve, ray/llm, ray/tune, ray/train, ray/air, ray/workflow; and the symbol tables of the
  native binaries (gcs_server, raylet, _raylet.so, libjemalloc.so: `strip --strip-unneeded`, their
  dynamic symbols stay). The RECORD is rewritten (sha256 and sizes of what is kept), the `serve` and
  `tune` console scripts are dropped, and ray/SLIM.txt says what was taken out.

Ray's own dependencies: its METADATA requires click, filelock, jsonschema, msgpack, packaging,
protobuf, pyyaml, requests; the GPU machine has all but jsonschema, which `import ray` needs
(ray.runtime_env's plugin schema manager): jsonschema, jsonschema-specifications, referencing and
rpds-py (binary) go into .whlr too. Options --python/--platform make it for another interpreter
(e.g. --python 3.11 to test the slim wheel on this machine).
"""
from __future__ import annotations

import argparse
import base64
import csv
import hashlib
import io
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

VERSION = "2.60.0"
STRIP_DIRS = ("ray/jars/", "ray/dashboard/client/build/", "ray/rllib/", "ray/data/", "ray/serve/", "ray/llm/",
              "ray/tune/", "ray/train/", "ray/air/", "ray/workflow/")
DROP_SCRIPTS = ("serve", "tune")
# What the lent GPU machine already has (its package list), by normalised name.
ON_GPU_MACHINE = {
    "aiohappyeyeballs", "aiohttp", "aiosignal", "attrs", "certifi", "charset-normalizer", "click", "cloudpickle",
    "filelock", "frozenlist", "fsspec", "grpcio", "idna", "jinja2", "msgpack", "multidict", "numpy", "packaging",
    "pandas", "pillow", "protobuf", "psutil", "pyarrow", "pyyaml", "requests", "tqdm", "typing-extensions",
    "urllib3", "yarl", "markupsafe", "propcache", "six", "python-dateutil", "pytz", "tzdata", "setuptools",
}


def norm(name: str) -> str:
    return name.lower().replace("_", "-").replace(".", "-")


def pip_download(args, requirements: list[str], dest: Path, deps: bool) -> None:
    cmd = [sys.executable, "-m", "pip", "download", "-q", "--only-binary=:all:", "--python-version", args.python,
           "--implementation", "cp", "-d", str(dest)]
    for platform in args.platform:
        cmd += ["--platform", platform]
    if not deps:
        cmd.append("--no-deps")
    subprocess.run(cmd + requirements, check=True)


def record_line(name: str, data: bytes) -> list:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return [name, f"sha256={digest}", str(len(data))]


def is_elf(data: bytes) -> bool:
    return data[:4] == b"\x7fELF"


def strip_elf(data: bytes, tmp: Path) -> bytes:
    """`data` with its symbol tables stripped (as is when `strip` is missing or fails)."""
    if not shutil.which("strip"):
        return data
    src, dst = tmp / "in", tmp / "out"
    src.write_bytes(data)
    try:
        subprocess.run(["strip", "--strip-unneeded", "-o", str(dst), str(src)], check=True, capture_output=True)
    except subprocess.CalledProcessError:
        return data
    return dst.read_bytes()


def slim(wheel: Path, out_dir: Path, strip: bool) -> Path:
    """Write the slim copy of `wheel` into `out_dir` (same file name); returns its path."""
    out = out_dir / wheel.name
    removed: dict[str, int] = {}
    stripped = []
    with zipfile.ZipFile(wheel) as zin, tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        info_dir = next(n.split("/")[0] for n in zin.namelist() if n.split("/")[0].endswith(".dist-info"))
        record_name = f"{info_dir}/RECORD"
        records = []
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as zout:
            for item in zin.infolist():
                name = item.filename
                top = next((d for d in STRIP_DIRS if name.startswith(d)), None)
                if top:
                    removed[top] = removed.get(top, 0) + item.file_size
                    continue
                if name == record_name or name.endswith("/"):
                    continue
                data = zin.read(item)
                if name == f"{info_dir}/entry_points.txt":
                    data = "".join(line for line in data.decode().splitlines(True)
                                   if line.split("=")[0].strip() not in DROP_SCRIPTS).encode()
                if strip and is_elf(data) and (name.endswith(".so") or "/core/src/" in name):
                    before = len(data)
                    data = strip_elf(data, tmp)
                    stripped.append(f"{name}: {before / 1e6:.1f} -> {len(data) / 1e6:.1f} MB")
                zi = zipfile.ZipInfo(name, item.date_time)
                zi.external_attr = item.external_attr     # keep the executables' mode bits
                zi.compress_type = zipfile.ZIP_DEFLATED
                zout.writestr(zi, data, compresslevel=9)
                records.append(record_line(name, data))
            note = ("Slimmed by rayvr's tools/ray_slim.py from " + wheel.name + " for rayvr.cluster (local Ray, no "
                    "dashboard UI, no Java, no libraries).\nRemoved (uncompressed bytes):\n" +
                    "".join(f"  {d} {n}\n" for d, n in removed.items()) +
                    "Symbol tables stripped:\n" + "".join(f"  {s}\n" for s in stripped)).encode()
            zi = zipfile.ZipInfo("ray/SLIM.txt", (2026, 1, 1, 0, 0, 0))
            zi.external_attr = 0o644 << 16
            zout.writestr(zi, note, zipfile.ZIP_DEFLATED)
            records.append(record_line("ray/SLIM.txt", note))
            buf = io.StringIO()
            writer = csv.writer(buf, lineterminator="\n")
            writer.writerows(records)
            writer.writerow([record_name, "", ""])
            zout.writestr(zipfile.ZipInfo(record_name, (2026, 1, 1, 0, 0, 0)), buf.getvalue(), zipfile.ZIP_DEFLATED)
    print(f"{wheel.name}: {wheel.stat().st_size / 1e6:.1f} MB -> {out.stat().st_size / 1e6:.1f} MB")
    for d, n in removed.items():
        print(f"  removed {d} ({n / 1e6:.1f} MB uncompressed)")
    for s in stripped:
        print(f"  stripped {s}")
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--version", default=VERSION, help=f"ray version (default {VERSION})")
    p.add_argument("--python", default="3.12", help="target Python (default 3.12: the GPU machine's)")
    p.add_argument("--platform", action="append", help="pip --platform tags (default manylinux2014_x86_64 "
                   "and manylinux_2_17_x86_64)")
    p.add_argument("--wheel", type=Path, help="an already downloaded ray wheel (else pip download)")
    p.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / ".whlr",
                   help="output folder (default .whlr at the repo root; emptied first)")
    p.add_argument("--no-strip", action="store_true", help="keep the binaries' symbol tables")
    p.add_argument("--no-deps", action="store_true", help="the slim ray wheel alone")
    args = p.parse_args()
    args.platform = args.platform or ["manylinux2014_x86_64", "manylinux_2_17_x86_64"]
    out = args.out
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        wheel = args.wheel
        if wheel is None:
            pip_download(args, [f"ray=={args.version}"], tmp, deps=False)
            wheel = next(tmp.glob("ray-*.whl"))
        slim(wheel, out, not args.no_strip)
        if not args.no_deps:
            with zipfile.ZipFile(wheel) as z:
                meta = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
                requires = [line.split(":", 1)[1].strip() for line in z.read(meta).decode().splitlines()
                            if line.startswith("Requires-Dist:") and "extra ==" not in line]
            deps = tmp / "deps"
            pip_download(args, requires, deps, deps=True)
            for whl in sorted(deps.glob("*.whl")):
                name = norm(whl.name.split("-")[0])
                if name in ON_GPU_MACHINE:
                    continue
                shutil.copy(whl, out / whl.name)
                print(f"  dependency {whl.name} ({whl.stat().st_size / 1e6:.2f} MB)")
    total = sum(f.stat().st_size for f in out.iterdir())
    print(f"{out}: {total / 1e6:.1f} MB ({total / 2**20:.1f} MiB) in {len(list(out.iterdir()))} wheels")
    return 0


if __name__ == "__main__":
    sys.exit(main())
