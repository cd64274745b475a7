"""A glTF file's bytes into its JSON document and GLB binary chunk, refusing broken structure.

A `.gltf` is UTF-8 JSON; a `.glb` is a 12-byte header (magic 'glTF', version 2, total length) and
chunks of (length, type, data): the JSON chunk first, then at most one BIN chunk (glTF 2.0
specification, "GLB File Format"). Every refusal is a SceneError naming the file and the part of
the container that is wrong (`GLB header.length`, `GLB chunk 1 (BIN)`, `JSON line 3 column 7`),
in the Khronos glTF-Validator's terms. JSON must be real JSON: NaN, Infinity and numbers that
overflow a double are refused, as is nesting too deep for the parser.
"""
from __future__ import annotations

import json
import math
import stat
import struct
from pathlib import Path

from ..errors import SceneError

GLB_MAGIC = b"glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942
CHUNK_NAMES = {CHUNK_JSON: "JSON", CHUNK_BIN: "BIN"}


def read_regular_file(path: Path, what: str) -> bytes:
    """The bytes of `path` if it is a regular file (not a device, FIFO or folder)."""
    try:
        st = path.stat()
    except OSError as exc:
        raise SceneError(f"{what}: cannot read ({exc.strerror})") from None
    if not stat.S_ISREG(st.st_mode):
        raise SceneError(f"{what}: not a regular file (a device, pipe or folder); give a file")
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as exc:
        raise SceneError(f"{what}: cannot read ({exc.strerror})") from None


def parse_json(text: bytes, where: str) -> dict:
    """Strict JSON (no NaN/Infinity, no overflowing numbers) whose root is an object."""
    def refuse_constant(name):
        raise ValueError(f"{name} is not a JSON number")

    def finite(token):
        value = float(token)
        if not math.isfinite(value):
            raise ValueError(f"number {token} does not fit a double")
        return value

    try:
        decoded = text.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(f"{where}: JSON is not UTF-8 text (byte {exc.start}); re-export the scene") from None
    try:
        doc = json.loads(decoded, parse_constant=refuse_constant, parse_float=finite)
    except json.JSONDecodeError as exc:
        raise SceneError(f"{where}: broken glTF JSON (line {exc.lineno} column {exc.colno}: {exc.msg}); "
                         f"re-export the scene") from None
    except ValueError as exc:
        raise SceneError(f"{where}: broken glTF JSON ({exc}); re-export the scene") from None
    except RecursionError:
        raise SceneError(f"{where}: JSON nests too deeply for a glTF file; re-export the scene") from None
    if not isinstance(doc, dict):
        raise SceneError(f"{where}: the JSON root is a {type(doc).__name__}, not an object; "
                         f"not a glTF file")
    return doc


def read_container(path: Path) -> tuple[dict, bytes | None, list[str]]:
    """(JSON document, GLB BIN chunk or None, warnings) of the glTF file at `path`."""
    data = read_regular_file(path, str(path))
    if data[:4] == GLB_MAGIC:
        return _read_glb(path, data)
    if path.suffix.lower() == ".glb":
        if not data:
            raise SceneError(f"{path}: GLB header: the file is empty; re-export the scene")
        hint = " (it holds JSON text: name it .gltf)" if data.lstrip()[:1] == b"{" else ""
        raise SceneError(f"{path}: GLB header.magic: {data[:4]!r} is not b'glTF'; not a binary glTF "
                         f"file{hint}")
    if not data.strip():
        raise SceneError(f"{path}: the file is empty; re-export the scene")
    return parse_json(data, str(path)), None, []


def _read_glb(path: Path, data: bytes) -> tuple[dict, bytes | None, list[str]]:
    if len(data) < 12:
        raise SceneError(f"{path}: GLB header: {len(data)} bytes, a GLB header needs 12 (truncated file); "
                         f"re-export the scene")
    _, version, length = struct.unpack_from("<4sII", data, 0)
    if version != 2:
        raise SceneError(f"{path}: GLB header.version: {version}; rayvr reads GLB version 2 (glTF 2.0)")
    if length != len(data):
        raise SceneError(f"{path}: GLB header.length: declares {length} bytes but the file has {len(data)} "
                         f"({'truncated' if length > len(data) else 'trailing bytes'}); re-export the scene")
    warnings: list[str] = []
    chunks: dict[int, bytes] = {}
    offset, index = 12, 0
    while offset < length:
        where = f"{path}: GLB chunk {index}"
        if length - offset < 8:
            raise SceneError(f"{where} header: {length - offset} bytes left, a chunk header needs 8 "
                             f"(truncated file)")
        size, kind = struct.unpack_from("<II", data, offset)
        name = CHUNK_NAMES.get(kind, f"0x{kind:08X}")
        where = f"{where} ({name})"
        if size % 4:
            raise SceneError(f"{where}.chunkLength: {size} is not a multiple of 4")
        if offset + 8 + size > length:
            raise SceneError(f"{where}.chunkLength: {size} bytes do not fit the {length - offset - 8} left "
                             f"in the file (truncated file)")
        if index == 0 and kind != CHUNK_JSON:
            raise SceneError(f"{where}: the first chunk must be JSON")
        if kind in chunks:
            raise SceneError(f"{where}: a second {name} chunk; a GLB has one")
        if kind == CHUNK_BIN and index != 1:
            raise SceneError(f"{where}: the BIN chunk must be the second chunk")
        if kind == CHUNK_JSON and size == 0:
            raise SceneError(f"{where}: the JSON chunk is empty")
        if kind in CHUNK_NAMES:
            chunks[kind] = data[offset + 8:offset + 8 + size]
        else:
            warnings.append(f"GLB chunk {index}: unknown chunk type {name} ignored")
        offset += 8 + size
        index += 1
    if CHUNK_JSON not in chunks:
        raise SceneError(f"{path}: GLB chunk 0: missing; the file ends after its header (truncated file)")
    return parse_json(chunks[CHUNK_JSON], f"{path}: GLB chunk 0 (JSON)"), chunks.get(CHUNK_BIN), warnings
