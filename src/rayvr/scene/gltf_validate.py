"""The glTF 2.0 rules a document must follow before rayvr reads any of its data.

Modelled on the Khronos glTF-Validator (its issue codes are named in the comments): JSON types
and required properties, value ranges, references between objects, buffer and accessor extents,
the node hierarchy (one parent per node, no loops, scenes list roots), cameras, and extensions
(declared in extensionsUsed, a required one must be implemented). What the validator calls an
error raises a SceneError naming the JSON path, e.g.
`scene.gltf: materials[2].pbrMetallicRoughness.roughnessFactor: 1.5 is out of range [0, 1]`;
what it calls a warning is returned as one line of text. Checks of the binary data (NaN
positions, vertex indices, sparse indices) are the loader's, where the data is decoded.

`validate(doc, where, supported, glb_bin_length)` is the entry point.
"""
from __future__ import annotations

import math
import re

from ..errors import SceneError

COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
COMPONENT_NAMES = {5120: "BYTE", 5121: "UNSIGNED_BYTE", 5122: "SHORT", 5123: "UNSIGNED_SHORT",
                   5125: "UNSIGNED_INT", 5126: "FLOAT"}
TYPE_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ATTRIBUTE_NAME = re.compile(r"^(POSITION|NORMAL|TANGENT|(TEXCOORD|COLOR|JOINTS|WEIGHTS)_\d+|_.*)$")
# Accessor formats a vertex attribute may have: (types, (componentType, normalized) pairs).
_UNORM = ((FLOAT, False), (UBYTE, True), (USHORT, True))
ATTRIBUTE_FORMATS = {"POSITION": (("VEC3",), ((FLOAT, False),)), "NORMAL": (("VEC3",), ((FLOAT, False),)),
                     "TANGENT": (("VEC4",), ((FLOAT, False),)), "TEXCOORD": (("VEC2",), _UNORM),
                     "COLOR": (("VEC3", "VEC4"), _UNORM)}
ROTATION_UNIT_TOLERANCE = 5e-4   # |q| within 1 +- this, as glTF-Validator allows


def _kind_of(value) -> str:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "number"
    return {str: "string", dict: "object", list: "array"}.get(type(value), type(value).__name__)


_KINDS = {"integer": ("integer",), "number": ("integer", "number"), "string": ("string",),
          "boolean": ("boolean",), "object": ("object",), "array": ("array",)}


def _interval(low, high, low_open, high_open) -> str:
    if high is None:
        return f"{'>' if low_open else '>='} {low:g}"
    if low is None:
        return f"{'<' if high_open else '<='} {high:g}"
    return f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"


class _Validator:
    def __init__(self, doc: dict, where: str, supported, glb_bin_length: int | None):
        self.doc, self.where = doc, where
        self.supported = frozenset(supported)
        self.glb_bin_length = glb_bin_length
        self.warnings: list[str] = []
        self.note = ""   # what the object being checked is used for, added to its errors

    # ---- primitives --------------------------------------------------------------------------
    def fail(self, path: str, what: str) -> SceneError:
        return SceneError(f"{self.where}: {path}: {what}{self.note}")

    def warn(self, path: str, what: str) -> None:
        self.warnings.append(f"{path}: {what}")

    def get(self, obj: dict, key: str, path: str, kind: str, required: bool = False):
        """obj[key] checked against the JSON kind ('integer', 'number', ...); None when absent."""
        if key not in obj:
            if required:   # [UNDEFINED_PROPERTY]
                raise self.fail(_join(path, key), "missing; the glTF specification requires it")
            return None
        value = obj[key]
        if _kind_of(value) not in _KINDS[kind]:   # [TYPE_MISMATCH]
            raise self.fail(_join(path, key),
                            f"{_short(value)} is a{'n' if _kind_of(value)[0] in 'aeiou' else ''} {_kind_of(value)}, "
                            f"not a{'n' if kind[0] in 'aeiou' else ''} {kind}")
        return value

    def number(self, obj: dict, key: str, path: str, low=None, high=None, low_open=False, high_open=False,
               required: bool = False, kind: str = "number", unit: str = ""):
        value = self.get(obj, key, path, kind, required)
        if value is not None:
            self.check_range(value, _join(path, key), low, high, low_open, high_open, unit)
        return value

    def check_range(self, value, path, low=None, high=None, low_open=False, high_open=False, unit="") -> None:
        bad = (low is not None and (value < low or (low_open and value == low))) or \
              (high is not None and (value > high or (high_open and value == high)))
        if bad:
            raise self.fail(path, f"{value:g} is out of range {_interval(low, high, low_open, high_open)}"
                                  f"{unit}; give a value in that range")

    def numbers(self, obj: dict, key: str, path: str, length: int | tuple, low=None, high=None,
                low_open=False, required: bool = False):
        """An array of `length` numbers, each in range."""
        value = self.get(obj, key, path, "array", required)
        if value is None:
            return None
        lengths = (length,) if isinstance(length, int) else length
        if len(value) not in lengths:
            raise self.fail(f"{path}.{key}", f"has {len(value)} elements, needs {' or '.join(map(str, lengths))}")
        for i, v in enumerate(value):
            if _kind_of(v) not in _KINDS["number"]:
                raise self.fail(f"{path}.{key}[{i}]", f"{_short(v)} is a {_kind_of(v)}, not a number")
            self.check_range(v, f"{path}.{key}[{i}]", low, high, low_open)
        return value

    def objects(self, key: str) -> list[dict]:
        """The top-level array `key` (absent: empty), every element an object."""
        items = self.get(self.doc, key, "", "array") or []
        for i, item in enumerate(items):
            if not isinstance(item, dict):
                raise self.fail(f"{key}[{i}]", f"{_short(item)} is a {_kind_of(item)}, not an object")
        return items

    def child(self, obj: dict, key: str, path: str, required: bool = False) -> dict | None:
        return self.get(obj, key, path, "object", required)

    def index(self, obj: dict, key: str, path: str, target: str, required: bool = False, noun: str = "") -> int | None:
        """obj[key]: an index into the top-level array `target` [UNRESOLVED_REFERENCE]."""
        value = self.get(obj, key, path, "integer", required)
        if value is not None:
            self.check_index(value, _join(path, key), target, noun)
        return value

    def check_index(self, value, path: str, target: str, noun: str = "") -> None:
        count = len(self.doc.get(target) or [])
        if _kind_of(value) != "integer":
            raise self.fail(path, f"{_short(value)} is a {_kind_of(value)}, not an index")
        if not 0 <= value < count:
            raise self.fail(path, f"{noun or target.rstrip('s')} {value} out of range ({count} {target})")

    def indices(self, obj: dict, key: str, path: str, target: str, noun: str = "") -> list[int]:
        """An array of distinct indices into `target` [DUPLICATE_ELEMENTS]."""
        value = self.get(obj, key, path, "array") or []
        seen = set()
        for i, v in enumerate(value):
            self.check_index(v, f"{path}.{key}[{i}]", target, noun)
            if v in seen:
                raise self.fail(f"{path}.{key}[{i}]", f"{v} is listed twice")
            seen.add(v)
        return value

    def enum(self, obj: dict, key: str, path: str, values, kind: str = "string", required: bool = False,
             error: bool = True):
        value = self.get(obj, key, path, kind, required)
        if value is not None and value not in values:
            what = f"{_short(value)} is not one of {', '.join(map(str, values))}"
            if error:
                raise self.fail(f"{path}.{key}", what)
            self.warn(f"{path}.{key}", what + "; the default is used")
            return None
        return value

    # ---- the document ------------------------------------------------------------------------
    def run(self) -> list[str]:
        self.asset()
        self.extensions_declared()
        self.buffers()
        self.buffer_views()
        self.accessors()
        self.images_samplers_textures()
        self.materials()
        self.meshes()
        self.cameras()
        self.lights()
        self.nodes_and_scenes()
        self.skins_and_animations()
        self.duplicate_names()
        return self.warnings

    def asset(self) -> None:
        asset = self.child(self.doc, "asset", "", required=True)
        version = self.get(asset, "version", "asset", "string", required=True)
        parsed = _version(version)
        if parsed is None:
            raise self.fail("asset.version", f"{version!r} is not MAJOR.MINOR (e.g. '2.0')")
        if parsed[0] != 2:   # [UNKNOWN_ASSET_MAJOR_VERSION]
            raise self.fail("asset.version", f"{version!r} is not glTF 2.x; rayvr reads glTF 2.0 "
                                             f"(re-export the scene as glTF 2.0)")
        min_version = self.get(asset, "minVersion", "asset", "string")
        if min_version is not None:
            parsed_min = _version(min_version)
            if parsed_min is None:
                raise self.fail("asset.minVersion", f"{min_version!r} is not MAJOR.MINOR")
            if parsed_min > parsed:   # [ASSET_MIN_VERSION_GREATER_THAN_VERSION]
                self.warn("asset.minVersion", f"{min_version!r} is greater than version {version!r}")
            if parsed_min > (2, 0):
                raise self.fail("asset.minVersion", f"the file needs a glTF {min_version} reader; rayvr reads "
                                                    f"glTF 2.0")
        if parsed[1] > 0:   # [UNKNOWN_ASSET_MINOR_VERSION]
            self.warn("asset.version", f"glTF {version} is newer than the 2.0 rayvr reads; what it adds is ignored")

    def extensions_declared(self) -> None:
        used = self._strings("extensionsUsed")
        required = self._strings("extensionsRequired")
        for i, name in enumerate(required):
            if name not in used:   # [UNUSED_EXTENSION_REQUIRED]
                raise self.fail(f"extensionsRequired[{i}]", f"'{name}' is required but not listed in extensionsUsed")
            if name not in self.supported:
                raise self.fail(f"extensionsRequired[{i}]",
                                f"the file requires '{name}', which rayvr does not implement (it implements "
                                f"{', '.join(sorted(self.supported))}); re-export the scene without it")
        for i, name in enumerate(used):   # [UNSUPPORTED_EXTENSION]
            if name not in self.supported and name not in required:
                self.warn(f"extensionsUsed[{i}]", f"'{name}' is not implemented by rayvr; what it adds is ignored")
        self._declared_everywhere(self.doc, "", set(used))

    def _strings(self, key: str) -> list[str]:
        items = self.get(self.doc, key, "", "array") or []
        for i, v in enumerate(items):
            if not isinstance(v, str):
                raise self.fail(f"{key}[{i}]", f"{_short(v)} is a {_kind_of(v)}, not a string")
            if v in items[:i]:   # [DUPLICATE_ELEMENTS]
                raise self.fail(f"{key}[{i}]", f"'{v}' is listed twice")
        return items

    def _declared_everywhere(self, value, path: str, used: set) -> None:
        """Every `extensions` object names only extensions of extensionsUsed [UNDECLARED_EXTENSION]."""
        stack = [(value, path)]
        while stack:
            value, path = stack.pop()
            if isinstance(value, dict):
                ext = value.get("extensions")
                if ext is not None:
                    if not isinstance(ext, dict):
                        raise self.fail(f"{path}.extensions" if path else "extensions",
                                        f"{_short(ext)} is a {_kind_of(ext)}, not an object")
                    for name, body in ext.items():
                        where = f"{path}.extensions.{name}" if path else f"extensions.{name}"
                        if name not in used:
                            raise self.fail(where, f"'{name}' is used but not declared in extensionsUsed; "
                                                   f"add it there")
                        if not isinstance(body, dict):
                            raise self.fail(where, f"{_short(body)} is a {_kind_of(body)}, not an object")
                for key, v in value.items():
                    if key != "extras" and isinstance(v, (dict, list)):
                        stack.append((v, f"{path}.{key}" if path else key))
            elif isinstance(value, list):
                stack.extend((v, f"{path}[{i}]") for i, v in enumerate(value) if isinstance(v, (dict, list)))

    # ---- binary data ---------------------------------------------------------------------------
    def buffers(self) -> None:
        for i, b in enumerate(self.objects("buffers")):
            f = f"buffers[{i}]"
            self.number(b, "byteLength", f, low=1, required=True, kind="integer")
            uri = self.get(b, "uri", f, "string")
            if uri is None:
                if self.glb_bin_length is None:   # [BUFFER_MISSING_GLB_DATA]
                    raise self.fail(f, "has no uri and the file has no GLB binary chunk")
                if i != 0:   # [BUFFER_NON_FIRST_GLB]
                    raise self.fail(f, "has no uri, but only buffers[0] can be the GLB binary chunk")
                if self.glb_bin_length < b["byteLength"]:
                    raise self.fail(f"{f}.byteLength", f"{b['byteLength']} bytes declared, the GLB binary chunk "
                                                       f"holds {self.glb_bin_length} (truncated file)")
                if self.glb_bin_length > b["byteLength"] + 3:   # [BUFFER_GLB_CHUNK_TOO_BIG]
                    self.warn(f"{f}.byteLength", f"the GLB binary chunk has {self.glb_bin_length - b['byteLength']} "
                                                 f"bytes more than declared")

    def buffer_views(self) -> None:
        buffers = self.doc.get("buffers") or []
        for i, bv in enumerate(self.objects("bufferViews")):
            f = f"bufferViews[{i}]"
            k = self.index(bv, "buffer", f, "buffers", required=True)
            offset = self.number(bv, "byteOffset", f, low=0, kind="integer") or 0
            length = self.number(bv, "byteLength", f, low=1, required=True, kind="integer")
            stride = self.number(bv, "byteStride", f, low=4, high=252, kind="integer")
            if stride is not None and stride % 4:   # [VALUE_MULTIPLE_OF]
                raise self.fail(f"{f}.byteStride", f"{stride} is not a multiple of 4")
            if stride is not None and stride > length:   # [BUFFER_VIEW_TOO_BIG_BYTE_STRIDE]
                raise self.fail(f"{f}.byteStride", f"{stride} is larger than byteLength {length}")
            self.enum(bv, "target", f, (34962, 34963), kind="integer", error=False)
            if offset + length > buffers[k]["byteLength"]:   # [BUFFER_VIEW_TOO_LONG]
                raise self.fail(f, f"bytes {offset}..{offset + length} do not fit buffers[{k}] "
                                   f"({buffers[k]['byteLength']} bytes)")

    def accessor_uses(self) -> dict[int, str]:
        """accessor index -> the first mesh attribute or indices field that reads it (for messages)."""
        uses: dict[int, str] = {}
        for i, mesh in enumerate(self.doc.get("meshes") or []):
            prims = mesh.get("primitives") if isinstance(mesh, dict) else None
            for j, prim in enumerate(prims if isinstance(prims, list) else []):
                if not isinstance(prim, dict):
                    continue
                attributes = prim.get("attributes")
                fields = list(attributes.items()) if isinstance(attributes, dict) else []
                for name, k in fields + [("indices", prim.get("indices"))]:
                    if _kind_of(k) == "integer":
                        where = "indices" if name == "indices" else f"attributes.{name}"
                        uses.setdefault(k, f"meshes[{i}].primitives[{j}].{where}")
        return uses

    def accessors(self) -> None:
        views = self.doc.get("bufferViews") or []
        uses = self.accessor_uses()
        # An accessor without a bufferView is zeros (plus sparse values): its count is bounded by
        # what the file could hold, so a hostile count is refused before anything is allocated.
        budget = max(sum(b["byteLength"] for b in self.doc.get("buffers") or []), 1 << 20)
        for i, a in enumerate(self.objects("accessors")):
            f = f"accessors[{i}]"
            self.note = f" (the accessor of {uses[i]})" if i in uses else ""
            ctype = self.enum(a, "componentType", f, tuple(COMPONENT_BYTES), kind="integer", required=True)
            kind = self.enum(a, "type", f, tuple(TYPE_COMPONENTS), required=True)
            count = self.number(a, "count", f, low=1, required=True, kind="integer")
            normalized = self.get(a, "normalized", f, "boolean")
            if normalized and ctype in (5125, 5126):   # [ACCESSOR_NORMALIZED_INVALID]
                raise self.fail(f"{f}.normalized", f"{COMPONENT_NAMES[ctype]} accessors cannot be normalized")
            width = TYPE_COMPONENTS[kind]
            for key in ("min", "max"):
                self.numbers(a, key, f, width)
            size = COMPONENT_BYTES[ctype]
            elem = size * width
            bv_index = self.index(a, "bufferView", f, "bufferViews", noun="bufferView")
            offset = self.number(a, "byteOffset", f, low=0, kind="integer") or 0
            if bv_index is None:
                if count * elem > budget:
                    raise self.fail(f"{f}.count", f"{count} elements ({count * elem} bytes) without a bufferView "
                                                  f"is more than the file's buffers hold; refused")
            else:
                self._fits(f, offset, count, elem, size, views[bv_index], bv_index)
            sparse = self.child(a, "sparse", f)
            if sparse is not None:
                self._sparse(f"{f}.sparse", sparse, count, elem, size, views)
        self.note = ""

    def _fits(self, f: str, offset: int, count: int, elem: int, size: int, view: dict, k: int) -> None:
        stride = view.get("byteStride") or elem
        if offset % size:   # [ACCESSOR_OFFSET_ALIGNMENT]
            raise self.fail(f"{f}.byteOffset", f"{offset} is not a multiple of the component size {size}")
        if ((view.get("byteOffset") or 0) + offset) % size:   # [ACCESSOR_TOTAL_OFFSET_ALIGNMENT]
            raise self.fail(f"{f}.byteOffset", f"bufferViews[{k}].byteOffset + byteOffset is not a multiple "
                                               f"of the component size {size}")
        if stride < elem:   # [ACCESSOR_SMALL_BYTESTRIDE]
            raise self.fail(f, f"bufferViews[{k}].byteStride {stride} is less than the element size {elem}")
        need = offset + stride * (count - 1) + elem
        if need > view["byteLength"]:   # [ACCESSOR_TOO_LONG]
            raise self.fail(f, f"{count} elements at offset {offset} run past the end of bufferViews[{k}] "
                               f"({view['byteLength']} bytes, {need} needed)")

    def _sparse(self, f: str, sparse: dict, count: int, elem: int, size: int, views: list) -> None:
        n = self.number(sparse, "count", f, low=1, required=True, kind="integer")
        if n > count:   # [ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE]
            raise self.fail(f"{f}.count", f"{n} overrides more elements than the accessor has ({count})")
        ind = self.child(sparse, "indices", f, required=True)
        k = self.index(ind, "bufferView", f"{f}.indices", "bufferViews", required=True, noun="bufferView")
        ictype = self.enum(ind, "componentType", f"{f}.indices", (UBYTE, USHORT, UINT), kind="integer",
                           required=True)
        ioff = self.number(ind, "byteOffset", f"{f}.indices", low=0, kind="integer") or 0
        isize = COMPONENT_BYTES[ictype]
        self._fits(f"{f}.indices", ioff, n, isize, isize, {**views[k], "byteStride": None}, k)
        val = self.child(sparse, "values", f, required=True)
        k = self.index(val, "bufferView", f"{f}.values", "bufferViews", required=True, noun="bufferView")
        voff = self.number(val, "byteOffset", f"{f}.values", low=0, kind="integer") or 0
        self._fits(f"{f}.values", voff, n, elem, size, {**views[k], "byteStride": None}, k)

    # ---- images, textures, materials -------------------------------------------------------------
    def images_samplers_textures(self) -> None:
        for i, img in enumerate(self.objects("images")):
            f = f"images[{i}]"
            uri = self.get(img, "uri", f, "string")
            bv = self.index(img, "bufferView", f, "bufferViews", noun="bufferView")
            mime = self.get(img, "mimeType", f, "string")
            if (uri is None) == (bv is None):   # [ONE_OF_MISMATCH]
                raise self.fail(f, "needs exactly one of uri and bufferView")
            if bv is not None and mime is None:   # [UNSATISFIED_DEPENDENCY]
                raise self.fail(f"{f}.mimeType", "missing; an image in a bufferView needs its mimeType")
            if mime is not None and mime not in ("image/png", "image/jpeg"):
                self.warn(f"{f}.mimeType", f"'{mime}' is not image/png or image/jpeg")
        for i, s in enumerate(self.objects("samplers")):
            f = f"samplers[{i}]"
            self.enum(s, "magFilter", f, (9728, 9729), kind="integer", error=False)
            self.enum(s, "minFilter", f, (9728, 9729, 9984, 9985, 9986, 9987), kind="integer", error=False)
            for key in ("wrapS", "wrapT"):
                self.enum(s, key, f, (33071, 33648, 10497), kind="integer", error=False)
        for i, t in enumerate(self.objects("textures")):
            f = f"textures[{i}]"
            self.index(t, "sampler", f, "samplers")
            self.index(t, "source", f, "images", noun="image")

    def texture_info(self, obj: dict, key: str, path: str, scale: str | None = None) -> None:
        info = self.child(obj, key, path)
        if info is None:
            return
        f = f"{path}.{key}"
        self.index(info, "index", f, "textures", required=True, noun="texture")
        self.number(info, "texCoord", f, low=0, kind="integer")
        if scale == "scale":
            self.number(info, "scale", f)
        elif scale == "strength":
            self.number(info, "strength", f, low=0, high=1)
        transform = (info.get("extensions") or {}).get("KHR_texture_transform")
        if transform is not None:
            t = f"{f}.extensions.KHR_texture_transform"
            self.numbers(transform, "offset", t, 2)
            self.number(transform, "rotation", t)
            self.numbers(transform, "scale", t, 2)
            self.number(transform, "texCoord", t, low=0, kind="integer")

    def materials(self) -> None:
        for i, m in enumerate(self.objects("materials")):
            f = f"materials[{i}]"
            self.get(m, "name", f, "string")
            pbr = self.child(m, "pbrMetallicRoughness", f)
            if pbr is not None:
                p = f"{f}.pbrMetallicRoughness"
                self.numbers(pbr, "baseColorFactor", p, 4, low=0, high=1)
                self.number(pbr, "metallicFactor", p, low=0, high=1)
                self.number(pbr, "roughnessFactor", p, low=0, high=1)
                self.texture_info(pbr, "baseColorTexture", p)
                self.texture_info(pbr, "metallicRoughnessTexture", p)
            self.texture_info(m, "normalTexture", f, "scale")
            self.texture_info(m, "occlusionTexture", f, "strength")
            self.texture_info(m, "emissiveTexture", f)
            self.numbers(m, "emissiveFactor", f, 3, low=0, high=1)
            mode = self.enum(m, "alphaMode", f, ("OPAQUE", "MASK", "BLEND"))
            cutoff = self.number(m, "alphaCutoff", f, low=0)
            if cutoff is not None and (mode or "OPAQUE") != "MASK":   # [MATERIAL_ALPHA_CUTOFF_INVALID_MODE]
                self.warn(f"{f}.alphaCutoff", "is used only with alphaMode MASK")
            self.get(m, "doubleSided", f, "boolean")
            for name, body in (m.get("extensions") or {}).items():
                rule = MATERIAL_EXTENSION_RULES.get(name)
                if rule is not None:
                    rule(self, body, f"{f}.extensions.{name}")

    # ---- meshes ----------------------------------------------------------------------------------
    def meshes(self) -> None:
        accessors = self.doc.get("accessors") or []
        views = self.doc.get("bufferViews") or []
        for i, mesh in enumerate(self.objects("meshes")):
            f = f"meshes[{i}]"
            self.get(mesh, "name", f, "string")
            prims = self.get(mesh, "primitives", f, "array", required=True)
            if not prims:
                raise self.fail(f"{f}.primitives", "is empty; a mesh needs at least one primitive")
            for j, prim in enumerate(prims):
                p = f"{f}.primitives[{j}]"
                if not isinstance(prim, dict):
                    raise self.fail(p, f"{_short(prim)} is a {_kind_of(prim)}, not an object")
                attributes = self.child(prim, "attributes", p, required=True)
                counts = {}
                for name in attributes:
                    if not ATTRIBUTE_NAME.match(name):   # [MESH_PRIMITIVE_INVALID_ATTRIBUTE]
                        raise self.fail(f"{p}.attributes.{name}", "is not a glTF attribute name")
                    k = self.index(attributes, name, f"{p}.attributes", "accessors", required=True)
                    counts[name] = accessors[k]["count"]
                    self._attribute_format(f"{p}.attributes.{name}", name, accessors[k], k)
                if len(set(counts.values())) > 1:   # [MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT]
                    raise self.fail(f"{p}.attributes", "accessors of different counts "
                                                       f"({', '.join(f'{n} {c}' for n, c in counts.items())})")
                if "POSITION" not in attributes:   # [MESH_PRIMITIVE_NO_POSITION]
                    self.warn(f"{p}.attributes", "no POSITION; the primitive is skipped")
                elif not ("min" in accessors[attributes["POSITION"]] and "max" in accessors[attributes["POSITION"]]):
                    raise self.fail(f"{p}.attributes.POSITION", f"accessors[{attributes['POSITION']}] has no min and "
                                                                f"max; POSITION accessors must declare their bounds")
                k = self.index(prim, "indices", p, "accessors")
                if k is not None:
                    a = accessors[k]
                    if a["type"] != "SCALAR" or a["componentType"] not in (UBYTE, USHORT, UINT) or a.get("normalized"):
                        raise self.fail(f"{p}.indices", f"accessors[{k}] is {_format(a)}; indices must be "
                                                        f"SCALAR UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT")
                    if a.get("bufferView") is not None and views[a["bufferView"]].get("byteStride") is not None:
                        raise self.fail(f"{p}.indices", f"bufferViews[{a['bufferView']}] has a byteStride; an index "
                                                        f"buffer view must not")
                self.index(prim, "material", p, "materials")
                mode = self.enum(prim, "mode", p, tuple(range(7)), kind="integer")
                n = accessors[k]["count"] if k is not None else next(iter(counts.values()), 0)
                if (mode is None or mode == 4) and n % 3:   # [MESH_PRIMITIVE_INCOMPATIBLE_MODE]
                    self.warn(p, f"{n} {'indices' if k is not None else 'vertices'} is not a multiple of 3 for "
                                 f"TRIANGLES; the last {n % 3} are ignored")
                for t, target in enumerate(self.get(prim, "targets", p, "array") or []):
                    if not isinstance(target, dict):
                        raise self.fail(f"{p}.targets[{t}]", f"{_short(target)} is not an object")
                    for name in target:
                        self.index(target, name, f"{p}.targets[{t}]", "accessors")

    def _attribute_format(self, path: str, name: str, a: dict, k: int) -> None:
        semantic = name.split("_")[0] if name[0] != "_" else name
        formats = ATTRIBUTE_FORMATS.get(semantic)
        if formats is None:
            return
        types, components = formats
        if a["type"] not in types or (a["componentType"], bool(a.get("normalized"))) not in components:
            allowed = " or ".join(types) + " of " + ", ".join(
                ("normalized " if norm else "") + COMPONENT_NAMES[c] for c, norm in components)
            raise self.fail(path, f"accessors[{k}] is {_format(a)}; {semantic} must be {allowed}")

    # ---- cameras and lights --------------------------------------------------------------------------
    def cameras(self) -> None:
        for i, cam in enumerate(self.objects("cameras")):
            f = f"cameras[{i}]"
            kind = self.enum(cam, "type", f, ("perspective", "orthographic"), required=True)
            body = self.child(cam, kind, f, required=True)
            p = f"{f}.{kind}"
            if kind == "perspective":
                self.number(body, "yfov", p, low=0, high=math.pi, low_open=True, high_open=True, required=True,
                            unit=" radians")
                self.number(body, "aspectRatio", p, low=0, low_open=True)
                znear = self.number(body, "znear", p, low=0, low_open=True, required=True, unit=" metres")
                zfar = self.number(body, "zfar", p, low=0, low_open=True, unit=" metres")
            else:
                for key in ("xmag", "ymag"):
                    if self.number(body, key, p, required=True) == 0:   # [CAMERA_XMAG_YMAG_ZERO]
                        self.warn(f"{p}.{key}", "is zero")
                znear = self.number(body, "znear", p, low=0, required=True, unit=" metres")
                zfar = self.number(body, "zfar", p, low=0, low_open=True, required=True, unit=" metres")
            if zfar is not None and zfar <= znear:   # [CAMERA_ZFAR_LEQUAL_ZNEAR]
                raise self.fail(f"{p}.zfar", f"{zfar:g} is not greater than znear {znear:g}")

    def lights(self) -> None:
        ext = (self.doc.get("extensions") or {}).get("KHR_lights_punctual")
        if ext is None:
            return
        f = "extensions.KHR_lights_punctual"
        lights = self.get(ext, "lights", f, "array", required=True)
        for i, light in enumerate(lights):
            p = f"{f}.lights[{i}]"
            if not isinstance(light, dict):
                raise self.fail(p, f"{_short(light)} is a {_kind_of(light)}, not an object")
            kind = self.enum(light, "type", p, ("point", "spot", "directional"), required=True)
            self.numbers(light, "color", p, 3, low=0, high=1)
            self.number(light, "intensity", p, low=0)
            self.number(light, "range", p, low=0, low_open=True, unit=" metres")
            spot = self.child(light, "spot", p)
            if kind == "spot" and spot is not None:
                s = f"{p}.spot"
                outer = self.number(spot, "outerConeAngle", s, low=0, high=math.pi / 2, low_open=True,
                                    unit=" radians")
                outer = math.pi / 4 if outer is None else outer
                self.number(spot, "innerConeAngle", s, low=0, high=outer, high_open=True, unit=" radians")

    # ---- the node hierarchy -------------------------------------------------------------------------
    def nodes_and_scenes(self) -> None:
        nodes = self.objects("nodes")
        lights = ((self.doc.get("extensions") or {}).get("KHR_lights_punctual") or {}).get("lights") or []
        parent: dict[int, int] = {}
        for i, node in enumerate(nodes):
            f = f"nodes[{i}]"
            self.get(node, "name", f, "string")
            self.index(node, "camera", f, "cameras")
            self.index(node, "mesh", f, "meshes")
            self.index(node, "skin", f, "skins")
            matrix = self.numbers(node, "matrix", f, 16)
            rotation = self.numbers(node, "rotation", f, 4, low=-1, high=1)
            self.numbers(node, "scale", f, 3)
            self.numbers(node, "translation", f, 3)
            if matrix is not None:
                if any(k in node for k in ("translation", "rotation", "scale")):   # [NODE_MATRIX_TRS]
                    raise self.fail(f, "has both a matrix and translation/rotation/scale; give one or the other")
                if matrix[3] != 0 or matrix[7] != 0 or matrix[11] != 0 or matrix[15] != 1:   # [NODE_MATRIX_NON_TRS]
                    raise self.fail(f"{f}.matrix", "is not an affine transform (the last row must be 0 0 0 1)")
            if rotation is not None:   # [NODE_ROTATION_NON_UNIT]
                norm = math.sqrt(sum(c * c for c in rotation))
                if abs(norm - 1) > ROTATION_UNIT_TOLERANCE:
                    raise self.fail(f"{f}.rotation", f"quaternion of length {norm:.6g}, not a unit quaternion")
            for c in self.indices(node, "children", f, "nodes", noun="node"):
                if c == i:
                    raise self.fail(f"{f}.children", f"node {i} lists itself; the node hierarchy has a cycle")
                if c in parent:   # [NODE_PARENT_OVERRIDE]
                    raise self.fail(f"{f}.children", f"node {c} already has parent nodes[{parent[c]}]; a node has "
                                                      f"at most one parent")
                parent[c] = i
            light = (node.get("extensions") or {}).get("KHR_lights_punctual")
            if light is not None:
                p = f"{f}.extensions.KHR_lights_punctual"
                k = self.get(light, "light", p, "integer", required=True)
                if not 0 <= k < len(lights):
                    raise self.fail(f"{p}.light", f"light {k} does not exist ({len(lights)} lights)")
        for start in parent:   # [NODE_LOOP]: with one parent each, a loop is a parent chain that returns
            seen, n = {start}, start
            while n in parent:
                n = parent[n]
                if n in seen:
                    raise self.fail(f"nodes[{n}].children", "the node hierarchy has a cycle")
                seen.add(n)
        for i, scene in enumerate(self.objects("scenes")):
            f = f"scenes[{i}]"
            for j, n in enumerate(self.indices(scene, "nodes", f, "nodes", noun="node")):
                if n in parent:   # [SCENE_NON_ROOT_NODE]
                    raise self.fail(f"{f}.nodes[{j}]", f"node {n} is a child of nodes[{parent[n]}], not a root")
        self.index(self.doc, "scene", "", "scenes")

    def skins_and_animations(self) -> None:
        for i, skin in enumerate(self.objects("skins")):
            f = f"skins[{i}]"
            self.index(skin, "inverseBindMatrices", f, "accessors")
            self.index(skin, "skeleton", f, "nodes", noun="node")
            if not self.get(skin, "joints", f, "array", required=True):
                raise self.fail(f"{f}.joints", "is empty")
            self.indices(skin, "joints", f, "nodes", noun="node")
        animations = self.objects("animations")
        for i, anim in enumerate(animations):
            f = f"animations[{i}]"
            samplers = self.get(anim, "samplers", f, "array", required=True)
            for j, s in enumerate(samplers):
                if not isinstance(s, dict):
                    raise self.fail(f"{f}.samplers[{j}]", f"{_short(s)} is not an object")
                self.index(s, "input", f"{f}.samplers[{j}]", "accessors", required=True)
                self.index(s, "output", f"{f}.samplers[{j}]", "accessors", required=True)
            for j, ch in enumerate(self.get(anim, "channels", f, "array", required=True)):
                c = f"{f}.channels[{j}]"
                if not isinstance(ch, dict):
                    raise self.fail(c, f"{_short(ch)} is not an object")
                s = self.get(ch, "sampler", c, "integer", required=True)
                if not 0 <= s < len(samplers):
                    raise self.fail(f"{c}.sampler", f"sampler {s} out of range ({len(samplers)} samplers)")
                target = self.child(ch, "target", c, required=True)
                self.index(target, "node", f"{c}.target", "nodes", noun="node")
        if animations:
            self.warn("animations", f"{len(animations)} animation(s) are not played; the scene renders at rest")

    def duplicate_names(self) -> None:
        """Names that repeat: valid glTF, but materials are addressed by name (`--effect`)."""
        for key in ("materials", "meshes", "nodes"):
            names = [o.get("name") for o in self.doc.get(key) or [] if isinstance(o.get("name"), str)]
            repeats = {n: names.count(n) for n in set(names) if names.count(n) > 1}
            if repeats:
                examples = ", ".join(f"'{n}' x{c}" for n, c in sorted(repeats.items())[:3])
                more = f" and {len(repeats) - 3} more" if len(repeats) > 3 else ""
                what = "later ones get '.1', '.2' suffixes" if key == "materials" else "they are told apart by index"
                self.warn(key, f"names repeat ({examples}{more}); {what}")


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _version(text: str) -> tuple[int, int] | None:
    m = re.fullmatch(r"(\d+)\.(\d+)", text)
    return (int(m.group(1)), int(m.group(2))) if m else None


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _format(a: dict) -> str:
    norm = "normalized " if a.get("normalized") else ""
    return f"{a['type']} {norm}{COMPONENT_NAMES[a['componentType']]}"


# Material extensions' value rules (KHR extension specifications). An entry validates the
# extension wherever it appears, implemented by the loader or not.
def _emissive_strength(v: _Validator, body: dict, f: str) -> None:
    v.number(body, "emissiveStrength", f, low=0)


def _transmission(v: _Validator, body: dict, f: str) -> None:
    v.number(body, "transmissionFactor", f, low=0, high=1)
    v.texture_info(body, "transmissionTexture", f)


def _ior(v: _Validator, body: dict, f: str) -> None:
    ior = v.number(body, "ior", f, low=0)
    if ior is not None and 0 < ior < 1:
        raise v.fail(f"{f}.ior", f"{ior:g} is out of range; give 0 or a value >= 1")


def _volume(v: _Validator, body: dict, f: str) -> None:
    v.number(body, "thicknessFactor", f, low=0)
    v.texture_info(body, "thicknessTexture", f)
    v.number(body, "attenuationDistance", f, low=0, low_open=True, unit=" metres")
    v.numbers(body, "attenuationColor", f, 3, low=0, high=1)


def _specular(v: _Validator, body: dict, f: str) -> None:
    v.number(body, "specularFactor", f, low=0, high=1)
    v.texture_info(body, "specularTexture", f)
    v.numbers(body, "specularColorFactor", f, 3, low=0)
    v.texture_info(body, "specularColorTexture", f)


MATERIAL_EXTENSION_RULES = {"KHR_materials_emissive_strength": _emissive_strength,
                            "KHR_materials_transmission": _transmission, "KHR_materials_ior": _ior,
                            "KHR_materials_volume": _volume, "KHR_materials_specular": _specular}


def validate(doc: dict, where: str, supported, glb_bin_length: int | None = None) -> list[str]:
    """Check `doc` (the parsed glTF JSON) against the rules above: raise SceneError on the first
    error, return the warnings. `supported`: the extensions the loader implements (a required one
    outside it is an error); `glb_bin_length`: bytes of the GLB BIN chunk (None: no chunk)."""
    return _Validator(doc, where, supported, glb_bin_length).run()
