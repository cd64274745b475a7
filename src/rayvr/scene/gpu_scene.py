"""The scene on the GPU: SSBOs at the bindings of `rayvr.gpu.bindings`, the two-level BVH, the
material/light tables and scene textures, and the one-call raster draw of every instance.

Layouts are declared in `glsl/scene.glsl`, `glsl/ray_query.glsl` and `glsl/lights.glsl`.
GpuScene builds what a scene's lifetime needs once (meshes, BLASes, textures, materials, the
emissive table); its `frame` (`gpu_frame.SceneFrame`) owns what changes per frame (instances and
the TLAS, punctual lights, the render-space shift). `update(origin)` uploads only what changed:
a head that moves rewrites the 32-byte shift, edits rebuild their part, materials re-upload when
`scene.materials.version` moved. `bvh_layout` (else `Scene.bvh_layout`, else
bvh_layouts.DEFAULT) picks the node layout of both BVH levels (bvh_layouts.py): "bvh2", "bvh4"
(the default), "bvh4q" (8-bit boxes: fewer bytes, but slower to trace on GPUs, its decode costing
more than its bytes save) or "bvh8" (compressed 8-wide nodes); ray_query.glsl follows the
RQ_BVH_WIDTH and RQ_BVH_QUANTIZED of `defines()`.
"""
from __future__ import annotations

import hashlib
import time

import numpy as np

from ..errors import GpuError, OptionError, SceneError
from ..gpu.bindings import BINDINGS
from ..gpu.records import MATERIAL_DATA, TEXTURE_ROWS, TEXTURE_SLOTS
from ..materials import bsdf_tables
from ..materials.material import Material
from . import bvh as bvh_mod
from . import bvh_layouts, bvh_wide, light_table
from .convex_faces import convex_faces
from .gpu_frame import SceneFrame
from .model import DEFAULT_ENVIRONMENT, FEATURES, Scene

MAX_TEXTURE_SIZE = 2048
TRIANGLE_CONVEX_BIT = 0x80000000   # glsl/scene.glsl: the whole mesh lies behind this triangle
MAX_ENVIRONMENT_HEIGHT = 1024   # environment maps above 2048x1024 are box-filtered down to it
GPU_BVH_MIN = 200_000         # 'auto' builds meshes this big on the GPU (hardware drivers only)
BVH_LAYOUTS = bvh_layouts.LAYOUTS


def scene_scale(scene: Scene) -> float:
    """The diagonal of the scene's bounds (1.0 for an empty scene), clamped to a sane range."""
    if not scene.instances:
        return 1.0
    lo, hi = np.asarray(scene.bounds(), dtype=np.float64)
    extent = float(np.linalg.norm(hi - lo))
    return float(np.clip(extent, 1e-6, 1e12)) if np.isfinite(extent) and extent > 0 else 1.0


def pack_materials(materials, texture_layers: dict[int, int] | None = None) -> np.ndarray:
    """The scene's material table: a `records.MATERIAL_DATA` record per material (one default
    material when there are none)."""
    mats = list(materials) or [Material()]
    out = MATERIAL_DATA.zeros(len(mats))
    tex = out["tex"]   # TEXTURE_ROWS rows per slot
    for i, m in enumerate(mats):
        out["base_color"][i] = m.base_color
        out["emission_cutoff"][i] = (*m.emission, m.alpha_cutoff)
        out["pbr"][i] = (m.metallic, m.roughness, m.transmission, min(m.ior, 1e30))
        out["flags"][i] = (int(m.effect), int(m.alpha_mode), int(bool(m.double_sided)), int(m.is_volume))
        out["specular"][i] = (*m.specular_color, m.specular)
        out["volume"][i] = (*m.attenuation_color, min(m.attenuation_distance, 3e38))
        out["extra"][i, 0] = m.thickness
        for s, slot in enumerate(TEXTURE_SLOTS):
            ref = getattr(m, f"{slot}_texture")
            layer = -1.0
            if ref is not None and texture_layers is not None and ref.texture in texture_layers:
                layer = float(texture_layers[ref.texture])
            mat = ref.uv_matrix() if ref is not None else np.array([[1.0, 0, 0], [0, 1.0, 0]])
            tex[i, TEXTURE_ROWS * s] = (*mat[0], layer)
            tex[i, TEXTURE_ROWS * s + 1] = (*mat[1], ref.strength if ref is not None else 1.0)
    return out


class GpuScene:
    """GPU buffers, BVH and textures of one `Scene`. Build once; `update(origin)` per frame."""

    LIGHT_SELECTIONS = ("power", "spatial")

    def __init__(self, gpu, scene: Scene, bvh_method: str = "auto", progress: bool | None = None,
                 bvh_layout: str | None = None):
        bvh_layout = bvh_layout or getattr(scene, "bvh_layout", None) or bvh_layouts.DEFAULT
        if bvh_layout not in BVH_LAYOUTS:
            raise SceneError(f"GpuScene bvh_layout: {bvh_layout!r}; use one of {BVH_LAYOUTS}")
        self.bvh_layout = bvh_layout
        self.gpu = gpu
        self.gl = gpu.gl if hasattr(gpu, "gl") else gpu
        self.scene = scene
        self.light_selection = getattr(scene, "light_selection", "power")
        if self.light_selection not in self.LIGHT_SELECTIONS:
            raise OptionError(f"scene '{scene.name}'.light_selection: {self.light_selection!r}; use one of "
                              f"{', '.join(self.LIGHT_SELECTIONS)}")
        self.features = scene.features
        self.timings: dict[str, float] = {}
        self.buffers: dict[str, object] = {}
        self.version = 0   # grows when update() uploads changed instances, lights or materials
        self._scale = None
        # each mesh's material ids, once (meshes keep their materials): the slots' alpha modes follow them
        self._mesh_material_ids = [np.unique(m.material_ids) for m in scene.meshes]
        self._slot_alpha_modes = self._alpha_modes()   # what the triangle slots hold (see _pack_mesh)
        self._build_meshes(bvh_method, progress)
        self._build_textures()
        self._material_version = None
        self._upload_materials()
        self._buffer("bsdf_tables", bsdf_tables.table_floats())   # glsl/bsdf.glsl's energy tables
        self.environment_texture = None
        self._build_lights()
        self._draws: dict[tuple, tuple | None] = {}   # (program id, instances per draw) -> (vao, commands, count, ids)
        self.frame = SceneFrame(self)
        self.update(np.zeros(3))

    # ---- static data ------------------------------------------------------------------------
    def upload(self, name: str, data) -> None:
        """Write `data` into buffer `name` (made, or remade when the size changes)."""
        self._buffer(name, data)

    def _buffer(self, name: str, data) -> None:
        data = np.ascontiguousarray(data)
        if data.nbytes == 0:
            data = np.zeros(4, np.uint32)
        limit = int(self.gl.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 1 << 31))
        if data.nbytes > limit:
            raise SceneError(f"scene '{self.scene.name}': the {name} buffer needs {data.nbytes / 2**20:.0f} MiB, "
                             f"more than this GPU's shader storage block limit ({limit / 2**20:.0f} MiB); "
                             f"render fewer triangles (split or decimate the meshes) or use a larger GPU")
        old = self.buffers.get(name)
        if old is not None and old.size == data.nbytes:
            old.write(data)
            return
        if old is not None:
            old.release()
        self.buffers[name] = self.gl.buffer(data)

    def _build_meshes(self, method: str, progress) -> None:
        """Build the BLASes and pack every mesh into the shared vertex, index, triangle-slot and
        BLAS-node buffers: each buffer allocated once at its total size, each mesh its slice."""
        self.convex_faces = self._convex_faces()   # timed apart from the BLAS builds
        t0 = time.perf_counter()
        s = self.scene
        built = self._build_blas(method, progress)
        collapsed = [isinstance(b, bvh_wide.WideBvh) for b in built]   # on the GPU already
        self.blas: list[bvh_mod.Bvh] = [b.source if c else b for b, c in zip(built, collapsed)]
        self._blas_gpu = [b if c or b is None else bvh_layouts.collapse_to(b, self.bvh_layout)
                          for b, c in zip(built, collapsed)]
        first_v = self._first_v = np.cumsum([0] + [len(m.positions) for m in s.meshes])
        first_t = self._first_t = np.cumsum([0] + [m.triangle_count for m in s.meshes])
        first_n = self._first_n = np.cumsum([0] + [0 if b is None else b.node_count for b in self._blas_gpu])
        self.triangle_count = t_total = int(first_t[-1])
        if t_total >= bvh_mod.MAX_LEAF_LINK or len(s.instances) >= bvh_mod.MAX_LEAF_LINK:
            raise SceneError(f"scene '{s.name}': {t_total} triangles / {len(s.instances)} instances; "
                             f"ray_query.glsl addresses at most {bvh_mod.MAX_LEAF_LINK - 1}; split the scene")
        normal_maps = "SCENE_HAS_NORMAL_MAPS" in self.features
        verts = np.zeros((first_v[-1], 8), np.float32)
        tangents = np.tile(np.array([1, 0, 0, 1], np.float32), (first_v[-1], 1)) if normal_maps else None
        idx = np.empty((t_total, 3), np.uint32)
        tri_mats = np.empty(t_total, np.uint32)
        slots = np.zeros((t_total, 3, 4), np.float32)   # a BVH slot per triangle (empty meshes have none)
        nodes = np.empty((first_n[-1], self.node_floats), np.float32)
        self.mesh_corners = np.zeros((max(len(s.meshes), 1), 8, 4))
        for k, mesh in enumerate(s.meshes):
            v, t, n = (slice(f[k], f[k + 1]) for f in (first_v, first_t, first_n))
            self._pack_mesh(k, verts[v], slots[t], nodes[n])
            if normal_maps and mesh.tangents is not None:
                tangents[v] = mesh.tangents
            idx[t] = mesh.indices + np.uint32(first_v[k])
            tri_mats[t] = self._triangle_words(k)
        self.mesh_live = np.array([b is not None for b in self.blas] or [False])
        any_mesh, any_bvh = bool(s.meshes), len(nodes) > 0
        self._buffer("vertices", verts if any_mesh else np.zeros((1, 8), np.float32))
        self._buffer("indices", idx if any_mesh else np.zeros(3, np.uint32))
        self._buffer("triangle_materials", tri_mats if any_mesh else np.zeros(1, np.uint32))
        self._buffer("triangles", slots if any_bvh else np.zeros((1, 3, 4), np.float32))
        self._buffer("blas_nodes", nodes if any_bvh else np.zeros((1, self.node_floats), np.float32))
        self.blas_roots = first_n[:-1].astype(np.uint32)        # per mesh, for the instances' records
        self.first_triangles = first_t[:-1].astype(np.uint32)
        if normal_maps:
            self._buffer("tangents", tangents)
        self.mesh_index_offsets = 3 * first_t
        self.timings["blas_build_ms"] = (time.perf_counter() - t0) * 1e3

    def _convex_faces(self) -> list[np.ndarray]:
        """Per mesh, its triangles with the whole mesh behind them (convex_faces), each distinct
        mesh once (instanced copies of one shape are often separate glTF meshes)."""
        t0 = time.perf_counter()
        seen: dict[tuple, np.ndarray] = {}
        out = []
        for m in self.scene.meshes:
            digest = hashlib.blake2b(m.positions, digest_size=16)   # the arrays' own buffers: no copies
            digest.update(m.indices)
            key = (m.positions.shape, m.indices.shape, digest.digest())
            if key not in seen:
                seen[key] = convex_faces(m.positions, m.indices)
            out.append(seen[key])
        self.timings["convex_faces_ms"] = (time.perf_counter() - t0) * 1e3
        return out

    def _triangle_words(self, k: int) -> np.ndarray:
        """Mesh k's per-triangle words of the triangle_materials buffer: the material id, and
        TRIANGLE_CONVEX_BIT where the whole mesh lies behind the triangle (glsl/scene.glsl)."""
        words = self.scene.meshes[k].material_ids.astype(np.uint32)
        return words | np.where(self.convex_faces[k], np.uint32(TRIANGLE_CONVEX_BIT), np.uint32(0))

    def _pack_mesh(self, k: int, verts: np.ndarray, slots: np.ndarray, nodes: np.ndarray) -> None:
        """Write mesh k's vertex rows, BVH slots and BLAS nodes (links offset to its place in the
        shared buffers) into the given arrays, which come zeroed (uvs and unused w stay 0); its
        object-space box into _mesh_corners."""
        mesh, b = self.scene.meshes[k], self.blas[k]
        verts[:, 0:3], verts[:, 4:7] = mesh.positions, mesh.normals
        if mesh.uvs is not None:
            verts[:, 3], verts[:, 7] = mesh.uvs[:, 0], mesh.uvs[:, 1]
        if b is None:
            return
        order = self._blas_gpu[k].order   # the traced layout's slot order (bvh8 has its own)
        slots[:, :, :3] = mesh.positions[mesh.indices[order]]
        slots.view(np.uint32)[:, 0, 3] = order
        slots.view(np.uint32)[:, 1, 3] = self._slot_alpha_modes[mesh.material_ids[order]]
        t_base = np.uint32(self._first_t[k])
        nodes[:] = self._blas_gpu[k].relinked(lambda slot: slot + t_base, int(self._first_n[k]))
        lo, hi = b.bounds()
        self.mesh_corners[k] = [[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]

    def _build_blas(self, method: str, progress) -> list:
        """One BLAS per mesh; several meshes build at once on a thread pool (numpy releases the
        GIL), a single big mesh uses the threaded LBVH itself. method 'gpu': every mesh on the
        GPU builder (bvh_gpu); 'auto': the GPU builder for meshes of GPU_BVH_MIN triangles and
        more on a hardware driver, binned SAH / LBVH on the CPU otherwise. Each a `Bvh`, except the
        GPU-built ones in layouts "bvh4" and "bvh8": collapsed on the GPU too, a `bvh_wide.WideBvh`
        or `bvh8.Bvh8` (greedy; the CPU-built ones get the SAH-optimal collapse in _build_meshes)."""
        import os
        from concurrent.futures import ThreadPoolExecutor

        from . import bvh_gpu

        if method not in ("auto", "gpu", "lbvh", "sah"):
            raise SceneError(f"GpuScene bvh_method: unknown {method!r}; use 'auto', 'gpu', 'lbvh' or 'sah'")
        caps = getattr(self.gpu, "caps", None)
        hardware = caps is not None and not caps.is_software
        on_gpu = [m.triangle_count > 0 and (method == "gpu" or (method == "auto" and hardware
                                                                  and m.triangle_count >= GPU_BVH_MIN))
                  for m in self.scene.meshes]
        build = {"bvh4": bvh_gpu.build_gpu_bvh4, "bvh8": bvh_gpu.build_gpu_bvh8}.get(self.bvh_layout, bvh_gpu.build_gpu)
        gpu_built = {k: build(self.gpu, m.triangles())   # GL calls: this thread only
                     for k, (m, g) in enumerate(zip(self.scene.meshes, on_gpu)) if g}
        if gpu_built:
            bvh_gpu.release_scratch(self.gpu)
        cpu_method = "auto" if method == "gpu" else method

        def one(mesh, threads=None):
            if not mesh.triangle_count:
                return None
            lo, hi = bvh_mod.triangle_bounds(mesh.triangles())
            return bvh_mod.build(lo, hi, method=cpu_method, progress=progress, threads=threads)

        meshes = [m for m, g in zip(self.scene.meshes, on_gpu) if not g]   # the rest, on the CPU
        if len(meshes) <= 1 or (os.cpu_count() or 1) == 1:
            cpu = [one(m) for m in meshes]
        else:
            big = [m.triangle_count >= bvh_mod.PARALLEL_MIN for m in meshes]
            out = [one(m) if b else None for m, b in zip(meshes, big)]
            with ThreadPoolExecutor(max_workers=os.cpu_count()) as pool:
                small = list(pool.map(lambda m: one(m, threads=1), [m for m, b in zip(meshes, big) if not b]))
            it = iter(small)
            cpu = [o if b else next(it) for o, b in zip(out, big)]
        it = iter(cpu)
        return [gpu_built[k] if g else next(it) for k, g in enumerate(on_gpu)]

    def _build_textures(self) -> None:
        self.texture_array = None
        self.texture_layers: dict[int, int] = {}
        if "SCENE_HAS_TEXTURES" not in self.features:
            return
        from PIL import Image

        used = sorted({ref.texture for m in self.scene.materials for ref in m.textures().values()
                       if 0 <= ref.texture < len(self.scene.textures)})
        images = [self.scene.textures[i].image for i in used]
        max_layers = int(self.gl.info.get("GL_MAX_ARRAY_TEXTURE_LAYERS", 256))
        if len(images) > max_layers:
            raise SceneError(f"scene '{self.scene.name}': {len(images)} textures, more than this GPU's "
                             f"{max_layers} texture array layers; merge textures into atlases")
        w = min(max(im.shape[1] for im in images), MAX_TEXTURE_SIZE)
        h = min(max(im.shape[0] for im in images), MAX_TEXTURE_SIZE)
        layers = []
        for im in images:
            if im.shape[:2] != (h, w):
                im = np.asarray(Image.fromarray(im).resize((w, h), Image.BILINEAR))
            layers.append(im)
        # Rows go up as stored (top row first), so GL's t = 0 is the image's top row, which is
        # exactly glTF's v = 0: uvs and KHR_texture_transform apply unchanged.
        data = np.ascontiguousarray(np.stack(layers), dtype=np.uint8)
        self.texture_array = self.gl.texture_array((w, h, len(layers)), 4, data.tobytes())
        self.texture_array.build_mipmaps()
        self.texture_array.repeat_x = self.texture_array.repeat_y = True
        self.texture_layers = {t: k for k, t in enumerate(used)}

    def _upload_materials(self) -> None:
        self._buffer("materials", pack_materials(self.scene.materials, self.texture_layers))
        self._material_version = self.scene.materials.version
        modes, held = self._alpha_modes(), self._slot_alpha_modes
        n = max(len(modes), len(held))
        changed = np.flatnonzero(np.pad(modes, (0, n - len(modes))) != np.pad(held, (0, n - len(held))))
        if len(changed):   # the triangle slots keep their material's alpha mode: rewrite the meshes that use these
            self._slot_alpha_modes = modes
            for k, ids in enumerate(self._mesh_material_ids):
                if self.blas[k] is not None and np.isin(ids, changed).any():
                    self._rewrite_mesh(k, ("triangles",))

    def _alpha_modes(self) -> np.ndarray:
        """Each material id's alpha mode (AlphaMode), for every id a mesh names (unknown ids: opaque)."""
        mats = self.scene.materials
        top = max([len(mats)] + [int(ids[-1]) + 1 for ids in self._mesh_material_ids if len(ids)])
        modes = np.zeros(top, np.uint32)
        modes[:len(mats)] = [int(m.alpha_mode) for m in mats]
        return modes

    def _build_emissive_triangles(self) -> np.ndarray:
        """The emissive triangles of every instance (world-space areas in float64) and their powers;
        degenerate (zero-area) triangles are left out. Uploads their ids; returns the powers."""
        self.emissive_count = 0
        self._clusters = []
        if "SCENE_HAS_EMISSIVE_TRIANGLES" not in self.features:
            return np.zeros(0)
        mats = list(self.scene.materials)
        lum = np.array([light_table.luminance(m.emission) for m in mats], np.float64)
        sides = np.array([2.0 if m.double_sided else 1.0 for m in mats])
        ids, power, clusters, first = [], [], [], 0
        for i, inst in enumerate(self.scene.instances):
            mesh = self.scene.meshes[inst.mesh]
            m = mesh.material_ids
            sel = np.flatnonzero(lum[m] > 0)
            if not len(sel):
                continue
            local = mesh.triangles()[sel].astype(np.float64)
            tri = local @ inst.transform[:3, :3].T
            area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
            p = np.pi * area * lum[m[sel]] * sides[m[sel]]
            keep = p > 0
            if not keep.any():
                continue
            ids.append(np.stack([np.full(int(keep.sum()), i), sel[keep], m[sel][keep],
                                 np.zeros(int(keep.sum()))], axis=1).astype(np.uint32))
            power.append(p[keep])
            clusters.append(light_table.emissive_cluster(i, local[keep], first, p[keep]))
            first += int(keep.sum())
        power = np.concatenate(power) if power else np.zeros(0)
        self._clusters = clusters
        if len(power):
            frame = getattr(self, "frame", None)   # none yet while the constructor builds
            head = self._cluster_rows(self.scene.instances.transforms,
                                      np.zeros(3) if frame is None else frame.anchor) if self.spatial_lights else None
            self._buffer("emissive_triangles", light_table.pack_emissive(np.concatenate(ids), power, clusters, head))
        self.emissive_count = len(power)
        return power

    @property
    def spatial_lights(self) -> bool:
        """Whether the scene asks for spatial light selection (Scene.light_selection)."""
        return self.light_selection == "spatial"

    def _cluster_rows(self, transforms, anchor) -> np.ndarray:
        return light_table.pack_clusters(self._clusters, transforms, anchor, spatial=self.spatial_lights)

    def write_emissive_clusters(self, transforms, anchor) -> None:
        """Rewrite the emissive clusters' anchor-space spheres (instances moved, or the anchor)."""
        if self.emissive_count and self.spatial_lights:
            self.buffers["emissive_triangles"].write(self._cluster_rows(transforms, anchor).tobytes())

    @property
    def emissive_clusters(self) -> int:
        """Emissive clusters the spatial light selection draws among (0: selection by power)."""
        return light_table.drawn_clusters(self._clusters, self.spatial_lights)

    def _build_lights(self) -> None:
        """The light table over every light (light_table.py), the emissive triangles and the
        environment; rebuilt when materials, punctual lights or the environment change."""
        radius = 0.5 * self.scale
        emissive = self._build_emissive_triangles()
        env = self.scene.lighting_environment()
        if env is not None and env.is_black:
            env = None
        if env is not None and env is DEFAULT_ENVIRONMENT and not getattr(self.scene, "_default_environment_noted", False):
            import warnings

            from ..errors import SceneWarning

            self.scene._default_environment_noted = True
            warnings.warn(f"{self.scene.name} has no light; lit by a neutral uniform environment of radiance 1 "
                          f"(set scene.environment to choose one)", SceneWarning, stacklevel=3)
        self.environment = env
        self.lights = light_table.build_light_table(light_table.punctual_powers(self.scene.lights, radius),
                                                    emissive, light_table.environment_power(env, radius))
        self._buffer("light_table", self.lights.packed())
        self._upload_environment(env)
        self._lights_key = (self.scene.lights.version, self.scene.materials.version, id(self.scene.environment))

    def _upload_environment(self, env) -> None:
        """The environment's colour, and for a map its texture and the CDFs of its importance
        sampling (luminance x sin(theta) per texel, as glsl/lights.glsl samples and evaluates it)."""
        if self.environment_texture is not None:
            self.environment_texture.release()
            self.environment_texture = None
        if env is None:
            return
        header = np.zeros(8, np.float32)
        header[0:3] = env.color
        cdf = np.zeros(1, np.float32)
        if env.image is not None:
            im = env.image
            if im.shape[0] > MAX_ENVIRONMENT_HEIGHT:   # a box filter down to the map's size
                k = int(np.ceil(im.shape[0] / MAX_ENVIRONMENT_HEIGHT))
                h2, w2 = im.shape[0] // k, im.shape[1] // k
                im = im[:h2 * k, :w2 * k].reshape(h2, k, w2, k, 3).mean(axis=(1, 3))
            im = np.ascontiguousarray(im, np.float32)
            h, w = im.shape[:2]
            sin_theta = np.sin((np.arange(h) + 0.5) / h * np.pi)
            weight = light_table.luminance(im.astype(np.float64)) * sin_theta[:, None]
            mean = float(weight.mean())
            rows = weight.sum(axis=1)
            marginal = np.cumsum(rows) / max(rows.sum(), 1e-300)
            conditional = np.cumsum(weight, axis=1) / np.maximum(rows[:, None], 1e-300)
            cdf = np.concatenate([marginal, conditional.reshape(-1)]).astype(np.float32)
            header.view(np.uint32)[4:6] = (w, h)
            header[6] = mean
            rgba = np.concatenate([im, np.ones((h, w, 1), np.float32)], axis=2)
            self.environment_texture = self.gl.texture((w, h), 4, rgba.tobytes(), dtype="f4")
            self.environment_texture.repeat_x, self.environment_texture.repeat_y = True, False
        self._buffer("environment", np.concatenate([header, cdf]))

    # ---- per frame --------------------------------------------------------------------------
    def update(self, origin=None) -> None:
        """Move to this frame's render-space origin (float64 world point) and upload what changed
        since the last frame: materials (`materials.version`), instances and the TLAS, lights
        (see gpu_frame.SceneFrame). `version` grows whenever something uploaded differs from the
        last frame's; a moving origin alone does not count (render space follows it)."""
        t0 = time.perf_counter()
        if self.scene.materials.version != self._material_version:
            self._upload_materials()
            self.version += 1
        if self._lights_key != (self.scene.lights.version, self.scene.materials.version, id(self.scene.environment)):
            self._build_lights()
            self.version += 1
        if self.frame.update(origin):
            self.version += 1
        self.timings["update_ms"] = (time.perf_counter() - t0) * 1e3

    @property
    def origin(self) -> np.ndarray:
        """The render-space origin of the last update (float64 world point)."""
        return self.frame.origin

    @property
    def node_floats(self) -> int:
        """Floats per BVH node of this scene's layout."""
        return bvh_layouts.NODE_FLOATS[self.bvh_layout]

    # ---- binding and drawing ----------------------------------------------------------------
    _BINDING = {"vertices": "RAYVR_VERTEX_SSBO", "indices": "RAYVR_INDEX_SSBO",
                "blas_nodes": "RAYVR_BLAS_NODE_SSBO", "tlas_nodes": "RAYVR_TLAS_NODE_SSBO",
                "instances": "RAYVR_INSTANCE_SSBO", "materials": "RAYVR_MATERIAL_SSBO",
                "punctual_lights": "RAYVR_PUNCTUAL_LIGHT_SSBO",
                "emissive_triangles": "RAYVR_EMISSIVE_TRIANGLE_SSBO", "triangles": "RAYVR_TRIANGLE_SSBO",
                "triangle_materials": "RAYVR_TRIANGLE_MATERIAL_SSBO",
                "tangents": "RAYVR_TANGENT_SSBO", "bsdf_tables": "RAYVR_BSDF_TABLE_SSBO",
                "light_table": "RAYVR_LIGHT_TABLE_SSBO", "environment": "RAYVR_ENVIRONMENT_SSBO"}

    def bind(self) -> None:
        """Bind every scene buffer to its SSBO point and the textures to the scene's unit."""
        for name, buf in self.buffers.items():
            buf.bind_to_storage_buffer(BINDINGS[self._BINDING[name]])
        if self.texture_array is not None:
            self.texture_array.use(BINDINGS["RAYVR_SCENE_TEXTURE_UNIT"])
        if self.environment_texture is not None:
            self.environment_texture.use(BINDINGS["RAYVR_ENVIRONMENT_TEXTURE_UNIT"])

    def defines(self) -> dict[str, int | str]:
        """The #defines every shader that includes the scene library is built with: the feature
        flags (0 or 1), SCENE_SCALE, the scene's extent in metres (ray offsets scale with it), and
        RQ_BVH_WIDTH and RQ_BVH_QUANTIZED, the node layout of the uploaded BVHs, and LIGHTS_SPATIAL
        (Scene.light_selection "spatial" in a scene with emissive triangles; else compiled out)."""
        have = set(self.features)
        if not self.emissive_count:   # every emissive triangle degenerate: no code samples an empty table
            have.discard("SCENE_HAS_EMISSIVE_TRIANGLES")
        if self.environment is None:
            have -= {"SCENE_HAS_ENVIRONMENT", "SCENE_HAS_ENVIRONMENT_MAP"}
        return {**{f: int(f in have) for f in FEATURES}, "SCENE_SCALE": repr(self.scale),
                "LIGHTS_SPATIAL": int(self.spatial_lights and "SCENE_HAS_EMISSIVE_TRIANGLES" in have),
                "RQ_CONVEX_SKIP": int(any(c.any() for c in self.convex_faces)),
                **bvh_layouts.DEFINES[self.bvh_layout]}

    @property
    def scale(self) -> float:
        """The diagonal of the scene's bounds when the GpuScene was built (1.0 for an empty scene),
        clamped to a sane range: what SCENE_SCALE compiles into the shaders."""
        if self._scale is None:
            self._scale = scene_scale(self.scene)
        return self._scale

    def draw(self, program, instances_per_draw: int = 1, mode=None) -> None:
        """Draw every instance in one glMultiDrawArraysIndirect (see scene.glsl): the program's
        vertex shader declares `in uint rayvr_instance;` and pulls vertices with
        scene_raster_vertex(rayvr_instance, gl_VertexID). Call bind() first."""
        import moderngl

        key = (id(program), instances_per_draw)
        if key not in self._draws:
            s = self.scene
            cmds, ids = [], np.repeat(np.arange(len(s.instances), dtype=np.uint32), instances_per_draw)
            for i, inst in enumerate(s.instances):
                mesh = s.meshes[inst.mesh]
                cmds.append((mesh.triangle_count * 3, instances_per_draw,
                             int(self.mesh_index_offsets[inst.mesh]), i * instances_per_draw))
            if not cmds:
                self._draws[key] = None
            else:
                # 5 uints per command: moderngl's render_indirect steps by the 20-byte stride of
                # DrawElementsIndirectCommand, also for array draws; the 5th word is padding.
                packed = np.zeros((len(cmds), 5), np.uint32)
                packed[:, :4] = cmds
                ibuf = self.gl.buffer(packed.tobytes())
                abuf = self.gl.buffer(ids.tobytes())
                try:
                    vao = self.gl.vertex_array(program, [(abuf, "1u /i", "rayvr_instance")])
                except (KeyError, moderngl.Error) as exc:
                    raise GpuError(f"GpuScene.draw: the program has no 'in uint rayvr_instance;' "
                                   f"vertex input ({exc}); declare it in the vertex shader") from exc
                self._draws[key] = (vao, ibuf, len(cmds), abuf)
        entry = self._draws[key]
        if entry is not None:
            entry[0].render_indirect(entry[1], mode=self.gl.TRIANGLES if mode is None else mode, count=entry[2])

    def refit(self, mesh: int, positions) -> None:
        """New vertex positions for mesh `mesh` (animation): its vertex rows, BVH triangles and
        BLAS boxes are rewritten in place (same topology; other meshes are not touched); the TLAS
        follows on the next update()."""
        m = self.scene.meshes[mesh]
        pos = np.ascontiguousarray(positions, dtype=np.float32).reshape(m.positions.shape)
        if not np.isfinite(pos).all():
            raise SceneError(f"mesh '{m.name}': refit positions contain NaN or Inf")
        m.positions = pos
        b = self.blas[mesh]
        if b is not None:
            b.refit(*bvh_mod.triangle_bounds(m.triangles()))
        names = ("vertices", "triangles", "blas_nodes")
        if self.convex_faces[mesh].any():   # a deforming mesh need not stay convex: no skipping
            self.convex_faces[mesh] = np.zeros(m.triangle_count, bool)
            names += ("triangle_materials",)
        self._rewrite_mesh(mesh, names)
        self.frame.invalidate()

    def _rewrite_mesh(self, k: int, names) -> None:
        """Pack mesh k again and write its slices of the named shared buffers."""
        m, b = self.scene.meshes[k], self.blas[k]
        v_base, t_base, n_base = (int(f[k]) for f in (self._first_v, self._first_t, self._first_n))
        verts = np.zeros((len(m.positions), 8), np.float32)
        slots = np.zeros((m.triangle_count, 3, 4), np.float32)
        nodes = np.empty((0 if b is None else self._blas_gpu[k].node_count, self.node_floats), np.float32)
        self._pack_mesh(k, verts, slots, nodes)
        for name, data, offset in (("vertices", verts, v_base * 32), ("triangles", slots, t_base * 48),
                                   ("blas_nodes", nodes, n_base * nodes.itemsize * self.node_floats),
                                   ("triangle_materials", self._triangle_words(k), t_base * 4)):
            if name in names and len(data):
                self.buffers[name].write(data, offset=offset)

    # ---- report -----------------------------------------------------------------------------
    @property
    def nbytes(self) -> int:
        """GPU bytes of the scene buffers and the texture array (with its mipmaps)."""
        n = sum(b.size for b in self.buffers.values())
        if self.texture_array is not None:
            w, h, layers = self.texture_array.size
            n += int(w * h * layers * 4 * 4 / 3)   # with mipmaps
        return n

    def report(self) -> dict:
        """Features present and left out (with the buffers not allocated), bytes per buffer."""
        absent = [f for f in FEATURES if f not in self.features]
        skipped = {
            "SCENE_HAS_PUNCTUAL_LIGHTS": "punctual_lights buffer",
            "SCENE_HAS_EMISSIVE_TRIANGLES": "emissive_triangles buffer",
            "SCENE_HAS_TEXTURES": "texture array",
            "SCENE_HAS_NORMAL_MAPS": "tangents buffer",
        }
        return {
            "scene": self.scene.name,
            "triangles": self.triangle_count,
            "instances": len(self.scene.instances),
            "features": sorted(self.features),
            "left_out": {f: skipped.get(f, "shader code only") for f in absent},
            "buffers": {k: v.size for k, v in self.buffers.items()},
            "texture_bytes": self.nbytes - sum(b.size for b in self.buffers.values()),
            "bytes_per_triangle": self.nbytes / max(self.triangle_count, 1),
            "geometry_bytes_per_triangle": sum(b.size for b in self.buffers.values()) / max(self.triangle_count, 1),
            "bvh_layout": self.bvh_layout,
            "blas_nodes": sum(b.node_count for b in self._blas_gpu if b is not None),
            "blas_node_bytes_per_triangle": sum(b.nbytes for b in self._blas_gpu if b is not None)
                                            / max(self.triangle_count, 1),
            "emissive_triangles": self.emissive_count,
            "convex_triangles": int(sum(int(c.sum()) for c in self.convex_faces)),
            "lights": {"table_entries": self.lights.count, "environment": self.environment.name if self.environment
                       else "none", "environment_probability": self.lights.probability_of(light_table.KIND_ENVIRONMENT)},
            "punctual_light_kinds": sorted({("point", "spot", "directional")[L.type] for L in self.scene.lights}),
            "timings_ms": dict(self.timings),
        }

    def release(self) -> None:
        """Free the scene's GPU buffers, texture array and the draw() vertex arrays."""
        for b in self.buffers.values():
            b.release()
        self.buffers.clear()
        for entry in self._draws.values():
            if entry is not None:
                vao, commands, _, ids = entry
                vao.release(), commands.release(), ids.release()
        self._draws.clear()
        if self.texture_array is not None:
            self.texture_array.release()
            self.texture_array = None
        if self.environment_texture is not None:
            self.environment_texture.release()
            self.environment_texture = None
