"""The glTF 2.0 metallic-roughness material (+ KHR_materials_emissive_strength, _transmission,
_ior, _volume and _specular) and the versioned table a scene keeps them in."""
from __future__ import annotations

import dataclasses
import enum
import math

import numpy as np

from ..errors import SceneError, did_you_mean
from ..gpu import records
from .effect import Effect


class AlphaMode(enum.IntEnum):
    """glTF alphaMode."""

    OPAQUE = 0
    MASK = 1
    BLEND = 2


@dataclasses.dataclass
class TextureRef:
    """A material's use of one image: index into `Scene.textures`, uv set and KHR_texture_transform."""

    texture: int
    texcoord: int = 0
    offset: tuple[float, float] = (0.0, 0.0)
    rotation: float = 0.0
    scale: tuple[float, float] = (1.0, 1.0)
    strength: float = 1.0   # normalTexture.scale / occlusionTexture.strength

    def uv_matrix(self) -> np.ndarray:
        """The 2x3 matrix KHR_texture_transform defines: T * R * S (uv' = M @ (u, v, 1))."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        rot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        sc = np.diag([self.scale[0], self.scale[1], 1.0])
        tr = np.array([[1.0, 0.0, self.offset[0]], [0.0, 1.0, self.offset[1]], [0.0, 0.0, 1.0]])
        return (tr @ rot @ sc)[:2]


# The texture fields of a Material, in the order of the material record's slots (TEX_* ids).
TEXTURE_SLOTS = tuple(f"{slot}_texture" for slot in records.TEXTURE_SLOTS)

# Fields whose change the GPU's material table must follow (every one pack_materials reads).
_VERSIONED = {"effect", "base_color", "metallic", "roughness", "emissive", "emissive_strength",
              "transmission", "ior", "alpha_mode", "alpha_cutoff", "double_sided", "specular",
              "specular_color", "thickness", "attenuation_color", "attenuation_distance", *TEXTURE_SLOTS}


@dataclasses.dataclass(eq=False)
class Material:
    """One glTF metallic-roughness material. Setting a field bumps the owning table's version."""

    name: str = "default"
    base_color: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    metallic: float = 1.0
    roughness: float = 1.0
    emissive: tuple[float, float, float] = (0.0, 0.0, 0.0)
    emissive_strength: float = 1.0
    transmission: float = 0.0
    ior: float = 1.5                      # inf: glTF's ior 0, the Fresnel term is 1 everywhere
    specular: float = 1.0                 # KHR_materials_specular: strength of the dielectric's specular layer
    specular_color: tuple[float, float, float] = (1.0, 1.0, 1.0)   # its F0 colour
    thickness: float = 0.0                # KHR_materials_volume: 0 thin-walled, > 0 a volume boundary
    attenuation_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    attenuation_distance: float = math.inf   # metres in which white light turns attenuation_color
    alpha_mode: AlphaMode = AlphaMode.OPAQUE
    alpha_cutoff: float = 0.5
    double_sided: bool = False
    base_color_texture: TextureRef | None = None
    metallic_roughness_texture: TextureRef | None = None
    normal_texture: TextureRef | None = None
    occlusion_texture: TextureRef | None = None
    emissive_texture: TextureRef | None = None
    transmission_texture: TextureRef | None = None
    specular_texture: TextureRef | None = None         # A channel x specular
    specular_color_texture: TextureRef | None = None   # RGB (sRGB) x specular_color
    thickness_texture: TextureRef | None = None        # G channel x thickness
    effect: Effect = Effect.SHADOWS

    def __setattr__(self, key, value):
        if key == "effect":
            value = Effect.parse(value, f"material '{self.__dict__.get('name', '?')}'.effect")
        elif key in _CHECKS:
            value = _CHECKS[key](self.__dict__.get("name", "?"), key, value)
        elif key == "alpha_mode" and not isinstance(value, AlphaMode):
            try:
                value = AlphaMode[str(value).upper()] if isinstance(value, str) else AlphaMode(value)
            except (KeyError, ValueError):
                raise SceneError(f"material '{self.__dict__.get('name', '?')}'.alpha_mode: unknown "
                                 f"{value!r}; use OPAQUE, MASK or BLEND") from None
        super().__setattr__(key, value)
        table = self.__dict__.get("_table")
        if table is not None and key in _VERSIONED:
            table.version += 1

    @property
    def is_volume(self) -> bool:
        """A closed volume (KHR_materials_volume thickness > 0) rather than a thin-walled surface."""
        return self.thickness > 0

    @property
    def emission(self) -> np.ndarray:
        """Emitted radiance factor: emissive * emissive_strength."""
        return np.asarray(self.emissive, dtype=np.float64) * self.emissive_strength

    @property
    def is_emissive(self) -> bool:
        """Whether any channel of `emission` is positive."""
        return bool(np.any(self.emission > 0))

    def textures(self) -> dict[str, TextureRef]:
        """The texture slots in use, by field name."""
        return {n: getattr(self, n) for n in TEXTURE_SLOTS if getattr(self, n) is not None}


def _number(name: str, key: str, value, low: float = -math.inf, high: float = math.inf,
            low_open: bool = False, allow_inf: bool = False) -> float:
    where = f"material '{name}'.{key}"
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise SceneError(f"{where}: {value!r} is not a number") from None
    if math.isnan(v) or (math.isinf(v) and not allow_inf):
        raise SceneError(f"{where}: {value!r} is not a finite number")
    if v < low or (low_open and v == low) or v > high:
        lo = f"({low:g}" if low_open else f"[{low:g}"
        raise SceneError(f"{where}: {v:g} is out of range {lo}, {high:g}]; fix the material")
    return v


def _color(name: str, key: str, value) -> tuple[float, float, float]:
    try:
        c = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        c = ()
    if len(c) != 3 or not all(math.isfinite(x) and x >= 0 for x in c):
        raise SceneError(f"material '{name}'.{key}: {value!r} is not three non-negative numbers (linear RGB)")
    return c


# Field checks: every value a material may hold is physical (one SceneError naming the field).
_CHECKS = {
    "ior": lambda n, k, v: _number(n, k, v, low=0.0, low_open=True, allow_inf=True),
    "attenuation_distance": lambda n, k, v: _number(n, k, v, low=0.0, low_open=True, allow_inf=True),
    "thickness": lambda n, k, v: _number(n, k, v, low=0.0),
    "metallic": lambda n, k, v: _number(n, k, v, 0.0, 1.0),
    "roughness": lambda n, k, v: _number(n, k, v, 0.0, 1.0),
    "transmission": lambda n, k, v: _number(n, k, v, 0.0, 1.0),
    "specular": lambda n, k, v: _number(n, k, v, 0.0, 1.0),
    "emissive_strength": lambda n, k, v: _number(n, k, v, low=0.0),
    "specular_color": _color,
    "attenuation_color": _color,
}


class MaterialTable:
    """Materials by index and by name; `version` grows whenever one of them changes."""

    def __init__(self, materials=()):
        self._items: list[Material] = []
        self._by_name: dict[str, int] = {}
        self.version = 0
        for m in materials:
            self.add(m)

    def add(self, material: Material) -> int:
        """Append a material (a duplicate name gets a '.1', '.2' suffix) and return its index."""
        name, k = material.name, 1
        while name in self._by_name:
            name = f"{material.name}.{k}"
            k += 1
        object.__setattr__(material, "name", name)
        object.__setattr__(material, "_table", self)
        self._by_name[name] = len(self._items)
        self._items.append(material)
        self.version += 1
        return len(self._items) - 1

    def index(self, name: str) -> int:
        """The index of the material called `name`; SceneError (with close names) if none is."""
        try:
            return self._by_name[name]
        except KeyError:
            raise SceneError(f"no material named '{name}'{did_you_mean(name, self._by_name)}; "
                             f"materials: {', '.join(self._by_name) or 'none'}") from None

    def __getitem__(self, key) -> Material:
        if isinstance(key, str):
            return self._items[self.index(key)]
        return self._items[key]

    def __len__(self) -> int:
        return len(self._items)

    def __iter__(self):
        return iter(self._items)

    def __contains__(self, name) -> bool:
        return name in self._by_name

    def names(self) -> list[str]:
        """Material names in index order."""
        return [m.name for m in self._items]
