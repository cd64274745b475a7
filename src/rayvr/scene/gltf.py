"""glTF 2.0 (.gltf / .glb) into a `Scene`: pygltflib parses the file, numpy decodes accessors,
Pillow decodes images. Every refusal is a SceneError naming the file and the glTF field.

Supported: node hierarchy (matrix or TRS) and instancing, triangle primitives (strips and fans
converted), metallic-roughness materials with textures and factors, alpha modes, doubleSided,
KHR_materials_emissive_strength, KHR_materials_transmission, KHR_materials_ior,
KHR_texture_transform, KHR_lights_punctual, perspective cameras, and material
`extras.rayvr_effect`. URIs must stay inside the scene's folder: anything else is refused
before it is read.
"""
from __future__ import annotations

import base64
import io
import json
import math
from pathlib import Path

import numpy as np

from ..errors import OptionError, SceneError
from ..materials.effect import Effect
from ..materials.material import AlphaMode, Material, TextureRef
from .model import Camera, Light, Mesh, Scene, Texture

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


class _Reader:
    def __init__(self, path: Path):
        import pygltflib

        self.path = path
        self.folder = path.parent.resolve()
        if not path.is_file():
            raise SceneError(f"{path}: file not found; check the path (built-in scenes: rayvr.scenes.cornell_box())")
        if path.suffix.lower() not in (".gltf", ".glb"):
            raise SceneError(f"{path}: not a glTF file; give a .gltf or .glb")
        try:
            self.doc = pygltflib.GLTF2().load(str(path))
        except (json.JSONDecodeError, UnicodeDecodeError, ValueError, KeyError, TypeError) as exc:
            raise SceneError(f"{path}: broken glTF JSON ({exc}); re-export the scene") from exc
        if self.doc is None:
            raise SceneError(f"{path}: could not be parsed as glTF; re-export the scene")
        self._buffers: dict[int, bytes] = {}

    def fail(self, field: str, what: str) -> SceneError:
        return SceneError(f"{self.path}: {field}: {what}")

    # ---- raw data ----------------------------------------------------------------------------
    def read_uri(self, uri: str, field: str) -> bytes:
        if uri.startswith("data:"):
            try:
                return base64.b64decode(uri.split(",", 1)[1])
            except (IndexError, ValueError) as exc:
                raise self.fail(field, f"bad data URI ({exc})") from exc
        from urllib.parse import unquote

        if "://" in uri:
            raise self.fail(field, f"URI '{uri}' is not a relative file; only files inside {self.folder} are read")
        target = (self.folder / unquote(uri)).resolve()
        if not target.is_relative_to(self.folder):
            raise self.fail(field, f"URI '{uri}' points outside the scene folder {self.folder}; refused "
                                   f"(copy the file next to the scene)")
        try:
            return target.read_bytes()
        except OSError as exc:
            raise self.fail(field, f"cannot read '{uri}' ({exc.strerror})") from exc

    def buffer(self, i: int) -> bytes:
        if i not in self._buffers:
            if not 0 <= i < len(self.doc.buffers):
                raise self.fail(f"buffers[{i}]", "index out of range")
            b = self.doc.buffers[i]
            if b.uri is None:
                blob = self.doc.binary_blob()
                if blob is None:
                    raise self.fail(f"buffers[{i}]", "no uri and no GLB binary chunk")
                self._buffers[i] = bytes(blob)
            else:
                self._buffers[i] = self.read_uri(b.uri, f"buffers[{i}].uri")
        return self._buffers[i]

    def buffer_view(self, i: int) -> tuple[bytes, int, int, int | None]:
        if i is None or not 0 <= i < len(self.doc.bufferViews):
            raise self.fail(f"bufferViews[{i}]", "index out of range")
        bv = self.doc.bufferViews[i]
        data = self.buffer(bv.buffer)
        start = bv.byteOffset or 0
        if start + bv.byteLength > len(data):
            raise self.fail(f"bufferViews[{i}]", f"bytes {start}..{start + bv.byteLength} out of range of "
                                                 f"buffers[{bv.buffer}] ({len(data)} bytes)")
        return data, start, bv.byteLength, bv.byteStride

    def accessor(self, i: int, field: str) -> np.ndarray:
        if i is None or not 0 <= i < len(self.doc.accessors):
            raise self.fail(field, f"accessor {i} out of range ({len(self.doc.accessors)} accessors)")
        a = self.doc.accessors[i]
        where = f"accessors[{i}] ({field})"
        if a.componentType not in _COMPONENT or a.type not in _WIDTH:
            raise self.fail(where, f"unsupported componentType {a.componentType} / type {a.type}")
        dtype = np.dtype(_COMPONENT[a.componentType]).newbyteorder("<")
        width = _WIDTH[a.type]
        if a.bufferView is None:
            out = np.zeros((a.count, width), dtype)
        else:
            data, start, length, stride = self.buffer_view(a.bufferView)
            elem = dtype.itemsize * width
            stride = stride or elem
            off = start + (a.byteOffset or 0)
            need = (a.count - 1) * stride + elem if a.count else 0
            if (a.byteOffset or 0) + need > length:
                raise self.fail(where, f"{a.count} elements at offset {a.byteOffset or 0} run past the end of "
                                       f"bufferViews[{a.bufferView}] ({length} bytes)")
            raw = np.frombuffer(data, np.uint8, count=need, offset=off) if a.count else np.zeros(0, np.uint8)
            if stride == elem:
                out = raw.view(dtype).reshape(a.count, width).copy()
            else:
                rows = np.lib.stride_tricks.as_strided(raw, (a.count, elem), (stride, 1))
                out = np.ascontiguousarray(rows).view(dtype).reshape(a.count, width)
        if a.sparse is not None:
            raise self.fail(where, "sparse accessors are not supported; re-export without sparse data")
        if a.normalized and dtype.kind in "ui":
            out = out.astype(np.float32) / np.float32(np.iinfo(dtype).max)
            if dtype.kind == "i":
                out = np.maximum(out, -1.0)
        return out


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
        self.warnings: list[str] = []

    def load(self) -> Scene:
        self._textures()
        self._materials()
        self._meshes()
        self._nodes()
        self.scene.warnings = self.warnings
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
                    raw = self.r.read_uri(img.uri, f"{field}.uri")
                elif img.bufferView is not None:
                    data, start, length, _ = self.r.buffer_view(img.bufferView)
                    raw = data[start:start + length]
                else:
                    raise self.r.fail(field, "neither uri nor bufferView")
                try:
                    with Image.open(io.BytesIO(raw)) as im:
                        images[src] = np.asarray(im.convert("RGBA"), dtype=np.uint8)
                except (UnidentifiedImageError, OSError, ValueError) as exc:
                    raise self.r.fail(field, f"image cannot be decoded ({exc}); use PNG or JPEG") from exc
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
                m.ior = float(ext["KHR_materials_ior"].get("ior", 1.5))
            extras = gm.extras or {}
            if isinstance(extras, dict) and "rayvr_effect" in extras:
                try:
                    m.effect = Effect.parse(extras["rayvr_effect"], f"{self.r.path}: {f}.extras.rayvr_effect")
                except OptionError as exc:
                    raise SceneError(str(exc)) from None
            for name, v in (("metallicFactor", m.metallic), ("roughnessFactor", m.roughness)):
                if not math.isfinite(v):
                    raise self.r.fail(f"{f}.{name}", f"{v} is not a finite number")
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
                    raise self.r.fail(f"{f}.attributes.POSITION", "missing")
                p = self.r.accessor(prim.attributes.POSITION, f"{f}.attributes.POSITION").astype(np.float32)
                if p.shape[1] != 3:
                    raise self.r.fail(f"{f}.attributes.POSITION", "must be VEC3")
                if not np.isfinite(p).all():
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
                if prim.material is None:
                    mid = self._default_material()
                elif not 0 <= prim.material < len(self.doc.materials or []):
                    raise self.r.fail(f"{f}.material", f"material {prim.material} does not exist")
                else:
                    mid = prim.material
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
        doc = self.doc
        lights_def = ((doc.extensions or {}).get("KHR_lights_punctual") or {}).get("lights", [])
        if doc.scenes:
            s = doc.scene if doc.scene is not None else 0
            if not 0 <= s < len(doc.scenes):
                raise self.r.fail("scene", f"scene {s} does not exist")
            roots = doc.scenes[s].nodes or []
        else:
            children = {c for n in doc.nodes or [] for c in (n.children or [])}
            roots = [i for i in range(len(doc.nodes or [])) if i not in children]
        stack = [(r, np.eye(4), ()) for r in reversed(roots)]
        while stack:
            ni, parent, path = stack.pop()
            if not 0 <= ni < len(doc.nodes or []):
                raise self.r.fail(f"nodes[{path[-1] if path else '?'}].children", f"node {ni} does not exist")
            if ni in path:
                raise self.r.fail(f"nodes[{ni}].children", "the node hierarchy has a cycle")
            node = doc.nodes[ni]
            world = parent @ _local_matrix(node)
            if not np.isfinite(world).all():
                raise self.r.fail(f"nodes[{ni}]", "transform is not finite")
            name = node.name or f"node{ni}"
            if node.mesh is not None:
                if node.mesh not in self.mesh_map:
                    raise self.r.fail(f"nodes[{ni}].mesh", f"mesh {node.mesh} does not exist")
                if self.mesh_map[node.mesh] is not None:
                    self.scene.add_instance(self.mesh_map[node.mesh], world, name)
            if node.camera is not None:
                if not 0 <= node.camera < len(doc.cameras or []):
                    raise self.r.fail(f"nodes[{ni}].camera", f"camera {node.camera} does not exist")
                cam = doc.cameras[node.camera]
                if cam.type == "perspective" and cam.perspective is not None:
                    p = cam.perspective
                    self.scene.cameras.append(Camera(world, float(p.yfov), p.aspectRatio, float(p.znear),
                                                     float(p.zfar) if p.zfar else 1000.0, cam.name or name))
                else:
                    self.warnings.append(f"cameras[{node.camera}]: only perspective cameras are used")
            lp = (node.extensions or {}).get("KHR_lights_punctual")
            if lp is not None:
                k = lp.get("light")
                if k is None or not 0 <= k < len(lights_def):
                    raise self.r.fail(f"nodes[{ni}].extensions.KHR_lights_punctual.light", f"light {k} does not exist")
                L = lights_def[k]
                kind = L.get("type")
                if kind not in ("point", "spot", "directional"):
                    raise self.r.fail(f"extensions.KHR_lights_punctual.lights[{k}].type",
                                      f"unknown {kind!r}; use point, spot or directional")
                spot = L.get("spot") or {}
                self.scene.lights.append(Light(
                    kind, position=world[:3, 3].copy(), direction=-world[:3, 2],
                    color=tuple(L.get("color", (1.0, 1.0, 1.0))), intensity=float(L.get("intensity", 1.0)),
                    range=float(L.get("range") or 0.0), inner_cone_angle=float(spot.get("innerConeAngle", 0.0)),
                    outer_cone_angle=float(spot.get("outerConeAngle", math.pi / 4)), name=L.get("name") or name))
            for c in reversed(node.children or []):
                stack.append((c, world, (*path, ni)))


def load_gltf(path) -> Scene:
    """Load a .gltf or .glb file (see the module docstring for what is read)."""
    return _Loader(Path(path)).load()
