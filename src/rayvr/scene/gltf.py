"""glTF 2.0 (.gltf / .glb) into a `Scene`. Every refusal is a SceneError naming the file and the
glTF field; every warning is one line in `Scene.warnings` (and a `rayvr.SceneWarning`).

Reading goes in three steps: `gltf_container` reads the file's bytes (strict JSON, the GLB
header and chunks), `gltf_validate` checks the document against the specification's rules as
the Khronos glTF-Validator does (types, ranges, references, extents, hierarchy, extensions)
before any data is read, and this module decodes the data (pygltflib's object model over the
validated JSON, numpy for accessors, Pillow for images) with the checks only the data allows
(NaN positions, vertex and sparse indices).

Supported: node hierarchy (matrix or TRS) and instancing, triangle primitives (strips and fans
converted), sparse accessors, metallic-roughness materials with textures and factors, alpha
modes, doubleSided, the extensions of SUPPORTED_EXTENSIONS, perspective cameras, and material
`extras.rayvr_effect`. URIs must name regular files inside the scene's folder: anything else
(parent folders, absolute paths, other schemes, devices) is refused before it is opened.
"""
from __future__ import annotations

import base64
import binascii
import io
import json
import math
import re
import stat
import warnings
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from ..errors import OptionError, SceneError, SceneWarning
from ..materials.effect import Effect
from ..materials.material import AlphaMode, Material, TextureRef
from .gltf_container import read_container
from .gltf_validate import validate
from .model import Camera, Light, Mesh, Scene, Texture

# The extensions this loader implements: a file may require these (extensionsRequired); any
# other required extension is refused, any other used one is ignored with a warning.
SUPPORTED_EXTENSIONS = frozenset({
    "KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior",
    "KHR_materials_specular", "KHR_materials_volume", "KHR_texture_transform", "KHR_lights_punctual"})

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")
_BUFFER_MIME = ("application/octet-stream", "application/gltf-buffer")
_IMAGE_MIME = ("image/png", "image/jpeg")


class _Reader:
    """The validated document and its bytes: buffers, buffer views, accessors, URIs."""

    def __init__(self, path: Path):
        import pygltflib

        self.path = path
        self.folder = path.parent.resolve()
        if not (path.exists() or path.is_symlink()):
            raise SceneError(f"{path}: file not found; check the path (built-in scenes: rayvr.scenes.cornell_box())")
        if path.suffix.lower() not in (".gltf", ".glb"):
            raise SceneError(f"{path}: not a glTF file; give a .gltf or .glb")
        doc, self.glb_bin, container_warnings = read_container(path)
        self.warnings = container_warnings + validate(doc, str(path), SUPPORTED_EXTENSIONS,
                                                      None if self.glb_bin is None else len(self.glb_bin))
        self.json = doc
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # dataclasses_json's notes on absent optional fields
            try:
                self.doc = pygltflib.GLTF2.from_json(json.dumps(doc))   # (from_dict keeps attributes as dicts)
            except (TypeError, ValueError, KeyError, AttributeError) as exc:
                raise SceneError(f"{path}: pygltflib cannot read the document ({exc}); re-export the scene") from None
        self._buffers: dict[int, bytes] = {}

    def fail(self, field: str, what: str) -> SceneError:
        return SceneError(f"{self.path}: {field}: {what}")

    # ---- raw data ----------------------------------------------------------------------------
    def read_uri(self, uri: str, field: str, mime_types, length: int | None = None) -> bytes:
        """The bytes `uri` names: a base64 data URI, or a regular file inside the scene folder
        (checked before it is opened); `length`: the declared byte count (a buffer's byteLength)."""
        if uri.startswith("data:"):
            return self._data_uri(uri, field, mime_types, length)
        if _SCHEME.match(uri) or uri.startswith(("/", "\\")) or "\\" in uri:
            raise self.fail(field, f"URI '{uri}' is an absolute path or URL, outside the scene folder "
                                   f"{self.folder}; refused (copy the file next to the scene)")
        target = (self.folder / unquote(uri)).resolve()
        if not target.is_relative_to(self.folder):
            raise self.fail(field, f"URI '{uri}' points outside the scene folder {self.folder}; refused "
                                   f"(copy the file next to the scene)")
        try:
            st = target.stat()
        except OSError as exc:
            raise self.fail(field, f"cannot read '{uri}' ({exc.strerror})") from None
        if not stat.S_ISREG(st.st_mode):
            raise self.fail(field, f"URI '{uri}' is not a regular file (a device, pipe or folder); refused")
        if length is not None and st.st_size < length:   # [BUFFER_EXTERNAL_BYTELENGTH_MISMATCH]
            raise self.fail(field, f"'{uri}' has {st.st_size} bytes, fewer than the declared byteLength {length}")
        try:
            with open(target, "rb") as f:
                return f.read(length if length is not None else -1)
        except OSError as exc:
            raise self.fail(field, f"cannot read '{uri}' ({exc.strerror})") from None

    def _data_uri(self, uri: str, field: str, mime_types, length: int | None) -> bytes:
        header, comma, payload = uri[5:].partition(",")
        if not comma or not header.endswith(";base64"):
            raise self.fail(field, "data URI is not base64 ('data:<mime>;base64,<data>'); re-export the scene")
        mime = header[:-len(";base64")]
        if mime_types and mime not in mime_types:   # [BUFFER_DATA_URI_MIME_TYPE_INVALID]
            raise self.fail(field, f"data URI of type '{mime}'; use {' or '.join(mime_types)}")
        try:
            data = base64.b64decode(payload, validate=True)
        except (binascii.Error, ValueError) as exc:
            raise self.fail(field, f"bad data URI ({exc})") from None
        if length is not None and len(data) != length:   # [BUFFER_EMBEDDED_BYTELENGTH_MISMATCH]
            raise self.fail(field, f"data URI holds {len(data)} bytes, the declared byteLength is {length}")
        return data

    def buffer(self, i: int) -> bytes:
        if i not in self._buffers:
            b = self.json["buffers"][i]
            if "uri" not in b:
                self._buffers[i] = self.glb_bin[:b["byteLength"]]
            else:
                self._buffers[i] = self.read_uri(b["uri"], f"buffers[{i}].uri", _BUFFER_MIME, b["byteLength"])
        return self._buffers[i]

    def buffer_view(self, i: int) -> tuple[bytes, int, int, int | None]:
        bv = self.json["bufferViews"][i]
        return self.buffer(bv["buffer"]), bv.get("byteOffset", 0), bv["byteLength"], bv.get("byteStride")

    def _elements(self, view: int, offset: int, count: int, dtype, width: int, stride: int | None) -> np.ndarray:
        """(count, width) elements of `dtype` from bufferViews[view] (extents are validated)."""
        data, start, _, view_stride = self.buffer_view(view)
        elem = dtype.itemsize * width
        stride = stride or view_stride or elem
        raw = np.frombuffer(data, np.uint8, count=(count - 1) * stride + elem, offset=start + offset)
        if stride == elem:
            return raw.view(dtype).reshape(count, width).copy()
        rows = np.lib.stride_tricks.as_strided(raw, (count, elem), (stride, 1))
        return np.ascontiguousarray(rows).view(dtype).reshape(count, width)

    def accessor(self, i: int, field: str) -> np.ndarray:
        a = self.json["accessors"][i]
        dtype = np.dtype(_COMPONENT[a["componentType"]]).newbyteorder("<")
        width, count = _WIDTH[a["type"]], a["count"]
        if a.get("bufferView") is None:
            out = np.zeros((count, width), dtype)
        else:
            out = self._elements(a["bufferView"], a.get("byteOffset", 0), count, dtype, width, None)
        sparse = a.get("sparse")
        if sparse is not None:
            self._apply_sparse(out, sparse, f"accessors[{i}].sparse ({field})", dtype, width)
        if a.get("normalized") and dtype.kind in "ui":
            out = out.astype(np.float32) / np.float32(np.iinfo(dtype).max)
            if dtype.kind == "i":
                out = np.maximum(out, -1.0)
        return out

    def _apply_sparse(self, out: np.ndarray, sparse: dict, where: str, dtype, width: int) -> None:
        """Overwrite the elements sparse.indices names with sparse.values (glTF 2.0, "Sparse Accessors")."""
        n, ind, val = sparse["count"], sparse["indices"], sparse["values"]
        idtype = np.dtype(_COMPONENT[ind["componentType"]]).newbyteorder("<")
        index = self._elements(ind["bufferView"], ind.get("byteOffset", 0), n, idtype, 1, idtype.itemsize)[:, 0]
        index = index.astype(np.int64)
        if n > 1 and not (np.diff(index) > 0).all():   # [ACCESSOR_SPARSE_INDICES_NON_INCREASING]
            k = int(np.argmin(np.diff(index) > 0)) + 1
            raise self.fail(f"{where}.indices", f"element {k} ({index[k]}) is not greater than the one before "
                                                f"({index[k - 1]}); sparse indices must increase")
        if index[-1] >= len(out):   # [ACCESSOR_SPARSE_INDEX_OOB]
            raise self.fail(f"{where}.indices", f"index {int(index[-1])} out of range for {len(out)} elements")
        out[index] = self._elements(val["bufferView"], val.get("byteOffset", 0), n, dtype, width,
                                    dtype.itemsize * width)


def _local_matrix(node) -> np.ndarray:
    if node.matrix is not None and len(node.matrix) == 16:
        return np.asarray(node.matrix, dtype=np.float64).reshape(4, 4).T
    m = np.eye(4)
    if node.rotation is not None:
        x, y, z, w = node.rotation
        n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
        x, y, z, w = x / n, y / n, z / n, w / n
        m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    if node.scale is not None:
        m[:3, :3] = m[:3, :3] * np.asarray(node.scale, dtype=np.float64)
    if node.translation is not None:
        m[:3, 3] = node.translation
    return m


def _triangles(mode: int, idx: np.ndarray) -> np.ndarray | None:
    if mode == 4:
        return idx[: len(idx) // 3 * 3].reshape(-1, 3)
    if mode == 5:   # strip: alternate winding
        n = len(idx) - 2
        if n <= 0:
            return np.zeros((0, 3), idx.dtype)
        k = np.arange(n)
        tri = np.stack([idx[k], idx[k + 1], idx[k + 2]], axis=1)
        odd = k % 2 == 1
        tri[odd] = tri[odd][:, [1, 0, 2]]
        return tri
    if mode == 6:   # fan
        n = len(idx) - 2
        if n <= 0:
            return np.zeros((0, 3), idx.dtype)
        k = np.arange(1, n + 1)
        return np.stack([np.full(n, idx[0]), idx[k], idx[k + 1]], axis=1)
    return None     # points and lines are not rendered


class _Loader:
    def __init__(self, path: Path):
        self.r = _Reader(path)
        self.doc = self.r.doc
        self.scene = Scene(path.stem, str(path))
        self.warnings: list[str] = list(self.r.warnings)

    def load(self) -> Scene:
        self._textures()
        self._materials()
        self._meshes()
        self._nodes()
        self.scene.warnings = [f"{self.r.path}: {w}" for w in dict.fromkeys(self.warnings)]
        for w in self.scene.warnings:
            warnings.warn(w, SceneWarning, stacklevel=4)   # the caller of rv.load_scene
        return self.scene

    # ---- textures and materials ------------------------------------------------------------
    def _textures(self) -> None:
        from PIL import Image, UnidentifiedImageError

        images: dict[int, np.ndarray] = {}
        for t_index, tex in enumerate(self.doc.textures or []):
            src = tex.source
            if src is None or not 0 <= src < len(self.doc.images or []):
                raise self.r.fail(f"textures[{t_index}].source", f"image {src} does not exist")
            if src not in images:
                img = self.doc.images[src]
                field = f"images[{src}]"
                if img.uri is not None:
                    raw = self.r.read_uri(img.uri, f"{field}.uri", None)
                else:
                    data, start, length, _ = self.r.buffer_view(img.bufferView)
                    raw = data[start:start + length]
                try:
                    with Image.open(io.BytesIO(raw)) as im:
                        images[src] = np.asarray(im.convert("RGBA"), dtype=np.uint8)
                except (UnidentifiedImageError, Image.DecompressionBombError, OSError, ValueError) as exc:
                    raise self.r.fail(field, f"image cannot be decoded ({exc}); use PNG or JPEG") from None
            self.scene.textures.append(Texture(images[src], name=tex.name or f"texture{t_index}"))

    def _texref(self, info, field: str, strength_attr: str | None = None) -> TextureRef | None:
        if info is None:
            return None
        index = info.index
        if index is None or not 0 <= index < len(self.scene.textures):
            raise self.r.fail(f"{field}.index", f"texture {index} does not exist ({len(self.scene.textures)} textures)")
        ref = TextureRef(index, info.texCoord or 0)
        if strength_attr is not None and getattr(info, strength_attr, None) is not None:
            ref.strength = float(getattr(info, strength_attr))
        tt = (info.extensions or {}).get("KHR_texture_transform")
        if tt:
            ref.offset = tuple(tt.get("offset", (0.0, 0.0)))
            ref.rotation = float(tt.get("rotation", 0.0))
            ref.scale = tuple(tt.get("scale", (1.0, 1.0)))
            if "texCoord" in tt:
                ref.texcoord = int(tt["texCoord"])
        return ref

    def _materials(self) -> None:
        class _Info:   # extension texture infos arrive as dicts
            def __init__(self, d):
                self.index, self.texCoord = d.get("index"), d.get("texCoord", 0)
                self.extensions = d.get("extensions")

        for i, gm in enumerate(self.doc.materials or []):
            f = f"materials[{i}]"
            m = Material(gm.name or f"material{i}")
            pbr = gm.pbrMetallicRoughness
            if pbr is not None:
                if pbr.baseColorFactor is not None:
                    m.base_color = tuple(float(c) for c in pbr.baseColorFactor)
                m.metallic = 1.0 if pbr.metallicFactor is None else float(pbr.metallicFactor)
                m.roughness = 1.0 if pbr.roughnessFactor is None else float(pbr.roughnessFactor)
                m.base_color_texture = self._texref(pbr.baseColorTexture, f"{f}.pbrMetallicRoughness.baseColorTexture")
                m.metallic_roughness_texture = self._texref(pbr.metallicRoughnessTexture,
                                                            f"{f}.pbrMetallicRoughness.metallicRoughnessTexture")
            m.normal_texture = self._texref(gm.normalTexture, f"{f}.normalTexture", "scale")
            m.occlusion_texture = self._texref(gm.occlusionTexture, f"{f}.occlusionTexture", "strength")
            m.emissive_texture = self._texref(gm.emissiveTexture, f"{f}.emissiveTexture")
            if gm.emissiveFactor is not None:
                m.emissive = tuple(float(c) for c in gm.emissiveFactor)
            mode = (gm.alphaMode or "OPAQUE").upper()
            if mode not in AlphaMode.__members__:
                raise self.r.fail(f"{f}.alphaMode", f"unknown {gm.alphaMode!r}; use OPAQUE, MASK or BLEND")
            m.alpha_mode = AlphaMode[mode]
            m.alpha_cutoff = 0.5 if gm.alphaCutoff is None else float(gm.alphaCutoff)
            m.double_sided = bool(gm.doubleSided)
            ext = gm.extensions or {}
            if "KHR_materials_emissive_strength" in ext:
                m.emissive_strength = float(ext["KHR_materials_emissive_strength"].get("emissiveStrength", 1.0))
            if "KHR_materials_transmission" in ext:
                tr = ext["KHR_materials_transmission"]
                m.transmission = float(tr.get("transmissionFactor", 0.0))
                if "transmissionTexture" in tr:
                    m.transmission_texture = self._texref(_Info(tr["transmissionTexture"]),
                                                          f"{f}.extensions.KHR_materials_transmission.transmissionTexture")
            if "KHR_materials_ior" in ext:
                ior = float(ext["KHR_materials_ior"].get("ior", 1.5))
                m.ior = math.inf if ior == 0 else ior   # 0: the specification's "Fresnel 1" mode
            if "KHR_materials_specular" in ext:
                sp = ext["KHR_materials_specular"]
                where = f"{f}.extensions.KHR_materials_specular"
                m.specular = float(sp.get("specularFactor", 1.0))
                m.specular_color = tuple(float(c) for c in sp.get("specularColorFactor", (1.0, 1.0, 1.0)))
                if "specularTexture" in sp:
                    m.specular_texture = self._texref(_Info(sp["specularTexture"]), f"{where}.specularTexture")
                if "specularColorTexture" in sp:
                    m.specular_color_texture = self._texref(_Info(sp["specularColorTexture"]),
                                                            f"{where}.specularColorTexture")
            if "KHR_materials_volume" in ext:
                vol = ext["KHR_materials_volume"]
                where = f"{f}.extensions.KHR_materials_volume"
                m.thickness = float(vol.get("thicknessFactor", 0.0))
                m.attenuation_color = tuple(float(c) for c in vol.get("attenuationColor", (1.0, 1.0, 1.0)))
                m.attenuation_distance = float(vol.get("attenuationDistance", math.inf))
                if "thicknessTexture" in vol:
                    m.thickness_texture = self._texref(_Info(vol["thicknessTexture"]), f"{where}.thicknessTexture")
            extras = gm.extras or {}
            if isinstance(extras, dict) and "rayvr_effect" in extras:
                try:
                    m.effect = Effect.parse(extras["rayvr_effect"], f"{self.r.path}: {f}.extras.rayvr_effect")
                except OptionError as exc:
                    raise SceneError(str(exc)) from None
            self.scene.add_material(m)

    def _default_material(self) -> int:
        if not hasattr(self, "_default"):
            self._default = self.scene.add_material(Material("default", metallic=0.0, roughness=1.0))
        return self._default

    # ---- meshes ------------------------------------------------------------------------------
    def _meshes(self) -> None:
        self.mesh_map: dict[int, int | None] = {}
        for mi, gmesh in enumerate(self.doc.meshes or []):
            pos, nrm, uv, tan, idx, mats = [], [], [], [], [], []
            base = 0
            has_n = all(p.attributes.NORMAL is not None for p in gmesh.primitives)
            has_uv = any(p.attributes.TEXCOORD_0 is not None for p in gmesh.primitives)
            has_t = all(p.attributes.TANGENT is not None for p in gmesh.primitives)
            for pi, prim in enumerate(gmesh.primitives):
                f = f"meshes[{mi}].primitives[{pi}]"
                mode = 4 if prim.mode is None else prim.mode
                if prim.attributes.POSITION is None:
                    continue   # the validator warned: nothing to draw
                p = self.r.accessor(prim.attributes.POSITION, f"{f}.attributes.POSITION").astype(np.float32)
                if not np.isfinite(p).all():   # [ACCESSOR_INVALID_FLOAT]
                    raise self.r.fail(f"{f}.attributes.POSITION", "contains NaN or Inf; fix the exporter")
                if prim.indices is not None:
                    ind = self.r.accessor(prim.indices, f"{f}.indices").reshape(-1).astype(np.int64)
                else:
                    ind = np.arange(len(p), dtype=np.int64)
                tri = _triangles(mode, ind)
                if tri is None:
                    self.warnings.append(f"{f}: mode {mode} (points/lines) skipped")
                    continue
                if len(tri) and (tri.max() >= len(p) or tri.min() < 0):
                    raise self.r.fail(f"{f}.indices", f"index {int(tri.max())} out of range for {len(p)} vertices")
                pos.append(p)
                idx.append(tri + base)
                base += len(p)
                if has_n:
                    nrm.append(self.r.accessor(prim.attributes.NORMAL, f"{f}.attributes.NORMAL").astype(np.float32))
                if has_uv:
                    if prim.attributes.TEXCOORD_0 is not None:
                        uv.append(self.r.accessor(prim.attributes.TEXCOORD_0, f"{f}.attributes.TEXCOORD_0").astype(np.float32))
                    else:
                        uv.append(np.zeros((len(p), 2), np.float32))
                if has_t:
                    tan.append(self.r.accessor(prim.attributes.TANGENT, f"{f}.attributes.TANGENT").astype(np.float32))
                mid = self._default_material() if prim.material is None else prim.material
                mats.append(np.full(len(tri), mid, np.uint32))
            if not pos:
                self.mesh_map[mi] = None
                continue
            cat = lambda xs: np.concatenate(xs) if xs else None  # noqa: E731
            normals = cat(nrm)
            if normals is not None and not np.isfinite(normals).all():
                normals = None   # recompute rather than shade with NaN
            mesh = Mesh(gmesh.name or f"mesh{mi}", cat(pos), cat(idx), cat(mats), normals=normals,
                        uvs=cat(uv), tangents=cat(tan))
            self.mesh_map[mi] = self.scene.add_mesh(mesh)

    # ---- node graph ----------------------------------------------------------------------------
    def _nodes(self) -> None:
        """Walk the default scene's node trees (references, single parents and the absence of
        loops are validated) into instances, cameras and lights."""
        doc = self.doc
        lights_def = ((doc.extensions or {}).get("KHR_lights_punctual") or {}).get("lights", [])
        if doc.scenes:
            roots = doc.scenes[doc.scene if doc.scene is not None else 0].nodes or []
        else:
            children = {c for n in doc.nodes or [] for c in (n.children or [])}
            roots = [i for i in range(len(doc.nodes or [])) if i not in children]
        stack = [(r, np.eye(4)) for r in reversed(roots)]
        while stack:
            ni, parent = stack.pop()
            node = doc.nodes[ni]
            world = parent @ _local_matrix(node)
            if not np.isfinite(world).all():
                raise self.r.fail(f"nodes[{ni}]", "transform is not finite")
            name = node.name or f"node{ni}"
            if node.mesh is not None and self.mesh_map[node.mesh] is not None:
                self.scene.add_instance(self.mesh_map[node.mesh], world, name)
            if node.camera is not None:
                cam = doc.cameras[node.camera]
                if cam.type == "perspective" and cam.perspective is not None:
                    p = cam.perspective
                    self.scene.cameras.append(Camera(world, float(p.yfov), p.aspectRatio, float(p.znear),
                                                     float(p.zfar) if p.zfar else 1000.0, cam.name or name))
                else:
                    self.warnings.append(f"cameras[{node.camera}]: only perspective cameras are used")
            lp = (node.extensions or {}).get("KHR_lights_punctual")
            if lp is not None:
                L = lights_def[lp["light"]]
                spot = L.get("spot") or {}
                self.scene.lights.append(Light(
                    L["type"], position=world[:3, 3].copy(), direction=-world[:3, 2],
                    color=tuple(L.get("color", (1.0, 1.0, 1.0))), intensity=float(L.get("intensity", 1.0)),
                    range=float(L.get("range") or 0.0), inner_cone_angle=float(spot.get("innerConeAngle", 0.0)),
                    outer_cone_angle=float(spot.get("outerConeAngle", math.pi / 4)), name=L.get("name") or name))
            for c in reversed(node.children or []):
                stack.append((c, world))


def load_gltf(path) -> Scene:
    """Load a .gltf or .glb file (see the module docstring for what is read)."""
    return _Loader(Path(path)).load()
