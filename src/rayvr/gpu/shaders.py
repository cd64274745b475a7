"""GLSL loading: `#include "file"`, injected `#define`s (binding points from `bindings.py` first), and compile errors named by file and line.

Includes are resolved against the including file's folder, then the package's shared GLSL folder
(`rayvr/glsl`), then the `rayvr` package root, so a pass writes `#include "ray_query.glsl"`.
A few includes are generated from Python tables (the G-buffer channels, the buffer records of
`records.py`), so the GLSL that reads a table can never drift from it: the table's module
registers its include (`register_include`).
Each file gets a GLSL source-string number through `#line`, which the error parser maps back
to its path. Programs are cached per (sources, defines): a pass built twice compiles once.
"""
from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import moderngl

from ..errors import ShaderError
from .bindings import BINDINGS
from .records import GLSL_INCLUDES as RECORD_INCLUDES

PACKAGE_ROOT = Path(__file__).resolve().parent.parent
SHARED_GLSL = PACKAGE_ROOT / "glsl"
GLSL_VERSION = "#version 450 core"

_INCLUDE = re.compile(r'^\s*#\s*include\s+[<"]([^>"]+)[>"]\s*(?://.*)?$')
_PRAGMA_ONCE = re.compile(r"^\s*#\s*pragma\s+once\s*$")
# Mesa: "0:12(3): error: ..."; NVIDIA: "0(12) : error C1008: ..."
_ERR_LOC = re.compile(r"(?m)^\s*(?:ERROR:\s*)?(\d+)(?::(\d+)\(\d+\)|\((\d+)\))")


class ShaderSource:
    """One preprocessed GLSL stage: final text plus the map from string numbers to files."""

    def __init__(self, text: str, files: list[Path]):
        self.text = text
        self.files = files

    def describe_error(self, log: str) -> str:
        """Rewrite driver locations ('0:12(3)' / '0(12)') as 'path:line'."""

        def sub(m: re.Match) -> str:
            idx = int(m.group(1))
            line = m.group(2) or m.group(3)
            name = str(self.files[idx]) if idx < len(self.files) else f"<string {idx}>"
            return f"{name}:{line}"

        return _ERR_LOC.sub(sub, log)


# include name -> the function returning its GLSL text
GENERATED_INCLUDES: dict[str, Callable[[], str]] = {}
GENERATED_DIR = Path("<generated>")


def register_include(name: str, source: Callable[[], str]) -> None:
    """Make `#include "name"` expand to `source()`, the GLSL generated from a Python table."""
    GENERATED_INCLUDES[name] = source



def _generated_text(path: Path) -> str:
    return GENERATED_INCLUDES[path.name]()


for _name, _source in RECORD_INCLUDES.items():    # the buffer records (gpu/records.py)
    register_include(_name, _source)


def _resolve(name: str, including_dir: Path, search: list[Path]) -> Path:
    if name in GENERATED_INCLUDES:
        return GENERATED_DIR / name
    for base in [including_dir, *search, SHARED_GLSL, PACKAGE_ROOT]:
        p = (base / name).resolve()
        if p.is_file():
            return p
    raise ShaderError(
        f"{including_dir}: #include \"{name}\" not found; looked in {including_dir}, "
        f"{', '.join(map(str, search)) + ', ' if search else ''}{SHARED_GLSL} and {PACKAGE_ROOT}"
    )


def _format_define(key: str, value) -> str:
    if value is True or value is None:
        return f"#define {key} 1"
    if value is False:
        return f"#define {key} 0"
    return f"#define {key} {value}"


def preprocess(path: str | Path, defines: dict | None = None, search: list[Path] | None = None,
               header: str = "") -> ShaderSource:
    """Expand includes of the GLSL file at `path` and prepend version, extensions and defines.

    `header` is raw GLSL placed after `#version` (extension directives must precede code).
    Each file is included once per stage: include guards are implicit, and they are preprocessor
    guards, so an #include inside a false #if leaves the file to a later #include.
    """
    path = Path(path).resolve()
    search = [Path(s) for s in (search or [])]
    files: list[Path] = []
    seen: dict[Path, int] = {}   # path -> its source-string number
    texts: dict[Path, list[str]] = {}
    out: list[str] = [GLSL_VERSION]
    if header:
        out.append(header)
    for k, v in {**BINDINGS, **(defines or {})}.items():
        out.append(_format_define(k, v))

    def emit(p: Path, stack: tuple[Path, ...]) -> None:
        if p in stack:
            chain = " -> ".join(s.name for s in (*stack, p))
            raise ShaderError(f"{p}: circular #include ({chain}); remove one of the includes")
        if p not in seen:
            seen[p] = len(files)
            files.append(p)
            try:
                texts[p] = (_generated_text(p) if p.parent == GENERATED_DIR else p.read_text()).splitlines()
            except OSError as exc:
                raise ShaderError(f"{p}: cannot read shader source: {exc}") from exc
        idx, lines = seen[p], texts[p]
        if stack:   # a guard, not a skip: an #include under a false #if must not use up the file
            out.extend((f"#ifndef RAYVR_INCLUDED_{idx}", f"#define RAYVR_INCLUDED_{idx}"))
        out.append(f"#line 1 {idx}")
        for n, line in enumerate(lines, start=1):
            m = _INCLUDE.match(line)
            if m:
                emit(_resolve(m.group(1), p.parent, search), (*stack, p))
                out.append(f"#line {n + 1} {idx}")
            elif _PRAGMA_ONCE.match(line) or line.lstrip().startswith("#version"):
                out.append("")
            else:
                out.append(line)
        if stack:
            out.append("#endif")

    emit(path, ())
    return ShaderSource("\n".join(out) + "\n", files)


_cache: dict[tuple, object] = {}


def _compile(gl: moderngl.Context, kind: str, sources: dict[str, ShaderSource], make):
    key = (id(gl), kind, tuple((k, s.text) for k, s in sorted(sources.items())))
    prog = _cache.get(key)
    if prog is not None:
        return prog
    try:
        prog = make()
    except moderngl.Error as exc:
        msg = str(exc)
        for s in sources.values():
            msg = s.describe_error(msg)
        first = next(iter(sources.values())).files[0]
        raise ShaderError(f"{first.name}: GLSL compile failed:\n{msg.strip()}") from exc
    _cache[key] = prog
    return prog


def compute_program(gl: moderngl.Context, path: str | Path, defines: dict | None = None,
                    header: str = "", search=None) -> moderngl.ComputeShader:
    """Build (or fetch from cache) a compute shader from a GLSL file."""
    src = preprocess(path, defines, search, header)
    return _compile(gl, "comp", {"comp": src}, lambda: gl.compute_shader(src.text))


def raster_program(gl: moderngl.Context, vertex: str | Path, fragment: str | Path | None = None,
                   defines: dict | None = None, header: str = "", geometry: str | Path | None = None,
                   search=None) -> moderngl.Program:
    """Build (or fetch from cache) a vertex/fragment (optionally geometry) program."""
    stages = {"vertex_shader": preprocess(vertex, defines, search, header)}
    if fragment is not None:
        stages["fragment_shader"] = preprocess(fragment, defines, search, header)
    if geometry is not None:
        stages["geometry_shader"] = preprocess(geometry, defines, search, header)
    return _compile(gl, "raster", stages, lambda: gl.program(**{k: v.text for k, v in stages.items()}))
