"""The CPU scene: meshes, instances, materials, lights and cameras (glTF's units and axes)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import SceneError
from ..materials.effect import Effect
from ..materials.material import AlphaMode, Material, MaterialTable

FEATURES = ("SCENE_HAS_PUNCTUAL_LIGHTS", "SCENE_HAS_EMISSIVE_TRIANGLES", "SCENE_HAS_ENVIRONMENT",
            "SCENE_HAS_ENVIRONMENT_MAP", "SCENE_HAS_TEXTURES", "SCENE_HAS_NORMAL_MAPS", "SCENE_HAS_ALPHA_MASK",
            "SCENE_HAS_ALPHA_BLEND", "SCENE_HAS_TRANSMISSION", "SCENE_HAS_INSTANCING")


@dataclasses.dataclass(eq=False)
class Mesh:
    """Object-space triangles. `material_ids` holds one material index per triangle."""

    name: str
    positions: np.ndarray                  # (V, 3) float32
    indices: np.ndarray                    # (T, 3) uint32
    material_ids: np.ndarray               # (T,) uint32
    normals: np.ndarray | None = None      # (V, 3) float32, computed when absent
    uvs: np.ndarray | None = None          # (V, 2) float32
    tangents: np.ndarray | None = None     # (V, 4) float32 (xyz, handedness)

    def __post_init__(self):
        self.positions = np.ascontiguousarray(self.positions, dtype=np.float32).reshape(-1, 3)
        self.indices = np.ascontiguousarray(self.indices, dtype=np.uint32).reshape(-1, 3)
        mids = np.asarray(self.material_ids, dtype=np.uint32)
        self.material_ids = np.ascontiguousarray(np.broadcast_to(mids, (len(self.indices),)))
        if not np.isfinite(self.positions).all():
            raise SceneError(f"mesh '{self.name}'.positions: NaN or Inf vertex; fix the exporter or drop the mesh")
        if len(self.indices) and int(self.indices.max()) >= len(self.positions):
            raise SceneError(f"mesh '{self.name}'.indices: index {int(self.indices.max())} out of range "
                             f"for {len(self.positions)} vertices")
        if self.normals is None:
            self.normals = vertex_normals(self.positions, self.indices)
        self.normals = np.ascontiguousarray(self.normals, dtype=np.float32).reshape(-1, 3)
        if self.uvs is not None:
            self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float32).reshape(-1, 2)
        if self.tangents is not None:
            self.tangents = np.ascontiguousarray(self.tangents, dtype=np.float32).reshape(-1, 4)

    @property
    def triangle_count(self) -> int:
        """Triangles of this mesh (one instance's worth)."""
        return len(self.indices)

    def triangles(self) -> np.ndarray:
        """(T, 3, 3) float32 vertex positions per triangle."""
        return self.positions[self.indices]


def vertex_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals; vertices of degenerate triangles only get +Y (never NaN)."""
    tri = positions[indices].astype(np.float64)
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    corner = indices.T.reshape(-1)   # all vertex-0 corners, then 1, then 2 (np.add.at's summation order)
    n = np.stack([np.bincount(corner, np.tile(fn[:, c], 3), minlength=len(positions)) for c in range(3)], axis=1)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    out = np.where(length > 1e-30, n / np.maximum(length, 1e-30), [0.0, 1.0, 0.0])
    return out.astype(np.float32)


class Instance:
    """One placement of a mesh: float64 4x4 object-to-world transform. An instance of a scene is
    a view of its row in the scene's InstanceTable: `inst.transform[:3, 3] = p` and
    `inst.transform = m` both move it."""

    __slots__ = ("_table", "_index", "_mesh", "_transform", "name")

    def __init__(self, mesh: int, transform=None, name: str = ""):
        self._table, self._index = None, -1
        self._mesh = int(mesh)
        self._transform = np.eye(4) if transform is None else np.asarray(transform, dtype=np.float64).reshape(4, 4).copy()
        self.name = name

    @property
    def mesh(self) -> int:
        return int(self._table.meshes[self._index]) if self._table is not None else self._mesh

    @mesh.setter
    def mesh(self, value: int) -> None:
        if self._table is not None:
            self._table.meshes[self._index] = int(value)
        else:
            self._mesh = int(value)

    @property
    def transform(self) -> np.ndarray:
        """The (4, 4) float64 object-to-world matrix (a view: writing into it moves the instance)."""
        return self._table.transforms[self._index] if self._table is not None else self._transform

    @transform.setter
    def transform(self, value) -> None:
        m = np.asarray(value, dtype=np.float64).reshape(4, 4)
        if self._table is not None:
            self._table.transforms[self._index] = m
        else:
            self._transform = m.copy()

    def __repr__(self) -> str:
        return f"Instance(mesh={self.mesh}, name={self.name!r})"


class InstanceTable:
    """A scene's instances: every transform in one (n, 4, 4) float64 array and every mesh index
    in one (n,) array, so per-frame work reads them without a loop over instances. Indexing and
    iteration give `Instance` views of the rows."""

    def __init__(self):
        self._transforms = np.zeros((0, 4, 4))
        self._meshes = np.zeros(0, np.int64)
        self._items: list[Instance] = []

    @property
    def transforms(self) -> np.ndarray:
        """(n, 4, 4) float64 object-to-world matrices (live: writes move the instances)."""
        return self._transforms[:len(self._items)]

    @property
    def meshes(self) -> np.ndarray:
        """(n,) mesh index per instance (live)."""
        return self._meshes[:len(self._items)]

    def append(self, inst: Instance) -> None:
        """Add `inst`, which becomes a view of its new row."""
        n = len(self._items)
        if n == len(self._transforms):   # grow by doubling: appends stay O(1) amortised
            cap = max(8, 2 * n)
            t, m = np.zeros((cap, 4, 4)), np.zeros(cap, np.int64)
            t[:n], m[:n] = self._transforms[:n], self._meshes[:n]
            self._transforms, self._meshes = t, m
        self._transforms[n] = inst.transform
        self._meshes[n] = inst.mesh
        inst._table, inst._index = self, n
        self._items.append(inst)

    def __len__(self) -> int:
        return len(self._items)

    def __getitem__(self, i) -> Instance:
        return self._items[i]

    def __iter__(self):
        return iter(self._items)

    def __bool__(self) -> bool:
        return bool(self._items)


class LightType:
    POINT = 0
    SPOT = 1
    DIRECTIONAL = 2
    NAMES = {"point": 0, "spot": 1, "directional": 2}


@dataclasses.dataclass(eq=False)
class Light:
    """A KHR_lights_punctual light placed in world space (intensity in candela or lux).

    A light in a scene's `lights` tells it when it changes (so the GPU re-uploads the lights only
    then): assign fields (`light.position = p`); the arrays are read-only so that in-place edits
    cannot slip past unseen."""

    type: int = LightType.POINT
    position: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    direction: np.ndarray = dataclasses.field(default_factory=lambda: np.array([0.0, 0.0, -1.0]))
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    range: float = 0.0                     # 0: infinite
    inner_cone_angle: float = 0.0
    outer_cone_angle: float = math.pi / 4
    name: str = ""

    def __setattr__(self, key, value):
        if key == "type" and isinstance(value, str):
            value = LightType.NAMES[value]
        elif key == "position":
            value = _frozen(np.asarray(value, dtype=np.float64).reshape(3))
        elif key == "direction":
            d = np.asarray(value, dtype=np.float64).reshape(3)
            value = _frozen(d / max(np.linalg.norm(d), 1e-30))
        elif key == "color":
            value = tuple(float(c) for c in value)
        super().__setattr__(key, value)
        owner = self.__dict__.get("_owner")
        if owner is not None:
            owner.version += 1


def _frozen(a: np.ndarray) -> np.ndarray:
    a = a.copy()
    a.flags.writeable = False
    return a


class LightList(list):
    """A scene's punctual lights; `version` grows whenever the list or one of its lights changes."""

    def __init__(self, lights=()):
        super().__init__()
        self.version = 0
        self.extend(lights)

    def __reduce__(self):   # pickling rebuilds through __init__ (the list's own protocol skips it)
        return (LightList, (list(self),))

    def _adopt(self, light) -> Light:
        if not isinstance(light, Light):
            raise SceneError(f"lights: {light!r} is not a rayvr.scene.Light")
        object.__setattr__(light, "_owner", self)
        self.version += 1
        return light

    def append(self, light) -> None:
        super().append(self._adopt(light))

    def extend(self, lights) -> None:
        for light in lights:
            self.append(light)

    def __iadd__(self, lights):
        self.extend(lights)
        return self

    def insert(self, i, light) -> None:
        super().insert(i, self._adopt(light))

    def __setitem__(self, i, light) -> None:
        if isinstance(i, slice):
            super().__setitem__(i, [self._adopt(x) for x in light])
        else:
            super().__setitem__(i, self._adopt(light))

    def _changed(self, result=None):
        self.version += 1
        return result

    def __delitem__(self, i):
        return self._changed(super().__delitem__(i))

    def pop(self, *args):
        return self._changed(super().pop(*args))

    def remove(self, light):
        return self._changed(super().remove(light))

    def clear(self):
        return self._changed(super().clear())


@dataclasses.dataclass(eq=False)
class Environment:
    """Light from every direction that no surface blocks: a uniform radiance `color`, or an
    equirectangular `image` of linear radiance (H, W, 3), W = 2 H, row 0 looking up (+Y), its
    centre column looking down -Z, scaled by `color`. `rayvr.scene.environment` loads files."""

    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    image: np.ndarray | None = None
    name: str = "environment"

    def __post_init__(self):
        c = tuple(float(x) for x in self.color)
        if len(c) != 3 or not all(math.isfinite(x) and x >= 0 for x in c):
            raise SceneError(f"environment '{self.name}'.color: {self.color!r} is not three non-negative numbers")
        self.color = c
        if self.image is not None:
            im = np.ascontiguousarray(self.image, dtype=np.float32)
            if im.ndim != 3 or im.shape[2] < 3 or im.shape[1] != 2 * im.shape[0]:
                raise SceneError(f"environment '{self.name}'.image: shape {im.shape} is not an equirectangular "
                                 f"(H, 2H, 3) image; give a 2:1 panorama")
            im = im[..., :3]
            if not np.isfinite(im).all() or (im < 0).any():
                raise SceneError(f"environment '{self.name}'.image: NaN, Inf or negative radiance; fix the file")
            self.image = im

    @property
    def is_black(self) -> bool:
        return not any(self.color) or (self.image is not None and not self.image.any())


DEFAULT_ENVIRONMENT = Environment((1.0, 1.0, 1.0), name="neutral default (the scene has no light)")


@dataclasses.dataclass
class Camera:
    """A perspective camera: world transform (looks down its -Z) and vertical field of view."""

    transform: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(4))
    yfov: float = math.radians(45.0)
    aspect: float | None = None
    znear: float = 0.05
    zfar: float = 1000.0
    name: str = ""

    def __post_init__(self):
        self.transform = np.asarray(self.transform, dtype=np.float64).reshape(4, 4)

    @property
    def position(self) -> np.ndarray:
        """World-space eye position (a copy of the transform's translation)."""
        return self.transform[:3, 3].copy()

    @classmethod
    def look_at(cls, eye, target, up=(0.0, 1.0, 0.0), yfov_deg: float = 45.0, name: str = "") -> "Camera":
        eye, target, up = (np.asarray(v, dtype=np.float64) for v in (eye, target, up))
        z = eye - target
        z /= np.linalg.norm(z)
        x = np.cross(up, z)
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, eye
        return cls(m, math.radians(yfov_deg), name=name)


@dataclasses.dataclass(eq=False)
class Texture:
    """An RGBA8 image (H, W, 4) uint8, row 0 at the top as in the file; `srgb` for colour data."""

    image: np.ndarray
    name: str = ""
    srgb: bool = True


class Scene:
    """Everything to render: meshes, instances, materials, textures, lights, cameras."""

    def __init__(self, name: str = "scene", path: str | None = None):
        self.name = name
        self.path = path
        self.meshes: list[Mesh] = []
        self.instances = InstanceTable()
        self.materials = MaterialTable()
        self.textures: list[Texture] = []
        self.lights = LightList()
        self.environment: Environment | None = None
        # how a shading point draws its light sample: "power" (one alias table over every light)
        # or "spatial" (lamps drawn by their irradiance estimate at the point: scene/light_table.py;
        # far fewer fireflies beside small lamps, a little more noise elsewhere; read when a
        # renderer builds its GpuScene)
        self.light_selection = "power"
        # the BVH node layout rays traverse (scene/bvh_layouts.py LAYOUTS; None: its DEFAULT), read
        # when a renderer builds its GpuScene
        self.bvh_layout: str | None = None
        self.cameras: list[Camera] = []
        self.warnings: list[str] = []          # what a loader skipped (e.g. line primitives)

    @property
    def lights(self) -> LightList:
        """The punctual lights (KHR_lights_punctual), a LightList."""
        return self._lights

    @lights.setter
    def lights(self, lights) -> None:
        self._lights = lights if isinstance(lights, LightList) else LightList(lights)

    def has_light(self) -> bool:
        """Whether anything lights the scene: a punctual light, an environment, or a material that
        emits without an emissive texture (a lamp, a light panel). Emission through a texture (a
        helmet's glowing details, a label, a screen) still emits and is sampled as light, but does
        not count: a scene lit by nothing else would render nearly black."""
        mats = [self.materials[i] for i in self.used_materials() if i < len(self.materials)]
        return bool(self.lights) or any(m.is_emissive and m.emissive_texture is None for m in mats) or (
            self.environment is not None and not self.environment.is_black)

    def lighting_environment(self) -> Environment | None:
        """The environment the scene is rendered with: its own, or DEFAULT_ENVIRONMENT when nothing
        at all lights it (a black image would tell nothing)."""
        if self.environment is not None:
            return self.environment
        return None if self.has_light() else DEFAULT_ENVIRONMENT

    # building -------------------------------------------------------------------------------
    def add_material(self, material: Material) -> int:
        """Append a material to `materials`; returns its index (see MaterialTable.add)."""
        return self.materials.add(material)

    def add_mesh(self, mesh: Mesh) -> int:
        """Append a mesh whose material ids exist; returns its index."""
        if len(mesh.material_ids) and int(mesh.material_ids.max()) >= max(len(self.materials), 1):
            raise SceneError(f"mesh '{mesh.name}'.material_ids: material {int(mesh.material_ids.max())} "
                             f"does not exist ({len(self.materials)} materials); add materials first")
        self.meshes.append(mesh)
        return len(self.meshes) - 1

    def add_instance(self, mesh: int, transform=None, name: str = "") -> int:
        """Place mesh `mesh` at `transform` (identity by default); returns the instance index."""
        if not 0 <= mesh < len(self.meshes):
            raise SceneError(f"instance '{name}'.mesh: index {mesh} out of range ({len(self.meshes)} meshes)")
        self.instances.append(Instance(mesh, np.eye(4) if transform is None else transform,
                                       name or self.meshes[mesh].name))
        return len(self.instances) - 1

    def add_object(self, name: str, positions, indices, material, transform=None, **attrs) -> int:
        """Add a mesh with one material (index or name) and one instance of it; returns the instance."""
        mid = self.materials.index(material) if isinstance(material, str) else int(material)
        mesh = self.add_mesh(Mesh(name, positions, indices, np.uint32(mid), **attrs))
        return self.add_instance(mesh, transform, name)

    # queries ---------------------------------------------------------------------------------
    @property
    def triangle_count(self) -> int:
        """Triangles over all instances."""
        return sum(self.meshes[i.mesh].triangle_count for i in self.instances)

    def bounds(self) -> np.ndarray:
        """World-space AABB over all instances: [[min xyz], [max xyz]] float64."""
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        mesh_boxes = {}   # once per mesh, not per instance
        meshes = self.instances.meshes
        if not len(meshes):
            return np.zeros((2, 3))
        for k in np.unique(meshes):   # once per mesh, not per instance
            p = self.meshes[k].positions
            if len(p):
                mesh_boxes[int(k)] = np.stack([p.min(axis=0), p.max(axis=0)]).astype(np.float64)
        live = np.array([int(k) in mesh_boxes for k in meshes])
        if not live.any():
            return np.zeros((2, 3))
        boxes = np.stack([mesh_boxes[int(k)] for k in meshes[live]])           # (n, 2, 3)
        corners = np.stack([boxes[:, [i, j, k], [0, 1, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)], axis=1)
        t = self.instances.transforms[live]
        w = np.einsum("nij,nkj->nki", t[:, :3, :3], corners) + t[:, None, :3, 3]
        lo, hi = np.minimum(lo, w.min(axis=(0, 1))), np.maximum(hi, w.max(axis=(0, 1)))
        if not np.isfinite(lo).all():
            return np.zeros((2, 3))
        return np.stack([lo, hi])

    def used_materials(self) -> set[int]:
        """Indices of the materials that some instanced mesh's triangles use."""
        used = set()
        for m in np.unique(self.instances.meshes):
            used.update(np.unique(self.meshes[int(m)].material_ids).tolist())
        return used

    def effects_used(self) -> set[Effect]:
        """The effects of the used materials (what the graph's ray passes must serve)."""
        return {self.materials[i].effect for i in self.used_materials() if i < len(self.materials)}

    @property
    def features(self) -> set[str]:
        """Names (FEATURES) of what the scene has; shaders compile code only for these."""
        mats = [self.materials[i] for i in self.used_materials() if i < len(self.materials)]
        f = set()
        if self.lights:
            f.add("SCENE_HAS_PUNCTUAL_LIGHTS")
        if any(m.is_emissive for m in mats):
            f.add("SCENE_HAS_EMISSIVE_TRIANGLES")
        if self.textures and any(m.textures() for m in mats):
            f.add("SCENE_HAS_TEXTURES")
        if self.textures and any(m.normal_texture is not None for m in mats):
            f.add("SCENE_HAS_NORMAL_MAPS")
        if any(m.alpha_mode == AlphaMode.MASK for m in mats):
            f.add("SCENE_HAS_ALPHA_MASK")
        if any(m.alpha_mode == AlphaMode.BLEND for m in mats):
            f.add("SCENE_HAS_ALPHA_BLEND")
        if any(m.transmission > 0 for m in mats):
            f.add("SCENE_HAS_TRANSMISSION")
        if len(self.instances) > len(np.unique(self.instances.meshes)):
            f.add("SCENE_HAS_INSTANCING")
        env = self.lighting_environment()
        if env is not None and not env.is_black:
            f.add("SCENE_HAS_ENVIRONMENT")
            if env.image is not None:
                f.add("SCENE_HAS_ENVIRONMENT_MAP")
        return f

    def __repr__(self) -> str:
        return (f"Scene({self.name!r}: {len(self.meshes)} meshes, {len(self.instances)} instances, "
                f"{self.triangle_count} triangles, {len(self.materials)} materials, {len(self.lights)} lights)")
