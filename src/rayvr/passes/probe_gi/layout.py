"""Where the probes are and how their data is laid out: probe volumes (world-space boxes with a
grid of probes at cell centres), the atlas of per-probe octahedral tiles, the ProbeVolumes
storage block that glsl/probe_gi.glsl reads, and numpy decoders of the atlas for tests and
benchmarks.

Atlas: probe i of all volumes (volume by volume, x fastest, then y, then z) owns tile
(i % columns, i // columns): 8x8 texels of irradiance and 16x16 of depth moments, each an
octahedral map with a one-texel border that repeats the opposite edge (Majercik et al. 2019), so
bilinear filtering never crosses into a neighbouring probe; one texel of state.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...errors import OptionError
from ...gpu.records import PROBE_VOLUME, PROBE_VOLUMES_HEADER_BYTES

IRRADIANCE_TILE = 8    # texels per side, border included (6x6 interior), as in glsl/probe_gi.glsl
DEPTH_TILE = 16        # (14x14 interior)
STATE_TILE = 1
VOLUME_HEADER_BYTES = PROBE_VOLUMES_HEADER_BYTES   # uvec4 probe_info
VOLUME_BYTES = PROBE_VOLUME.size                  # one ProbeVolume record
FLAG_VISIBILITY = 1        # probe_info.w bit: Chebyshev visibility on


@dataclasses.dataclass(frozen=True)
class ProbeVolume:
    """A box in world space (metres, float64) with `counts` probes per axis at its cell centres."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    counts: tuple[int, int, int]

    @property
    def probe_count(self) -> int:
        return int(np.prod(self.counts))

    @property
    def spacing(self) -> np.ndarray:
        return (np.asarray(self.hi, np.float64) - np.asarray(self.lo, np.float64)) / np.asarray(self.counts)

    @property
    def first_probe_position(self) -> np.ndarray:
        return np.asarray(self.lo, np.float64) + 0.5 * self.spacing

    def positions(self) -> np.ndarray:
        """World positions (n, 3) of its probes, in atlas order (x fastest, then y, then z)."""
        nx, ny, nz = self.counts
        z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
        cells = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
        return self.first_probe_position + cells * self.spacing

    def as_dict(self) -> dict:
        """Plain JSON values (a pass property round-trips through it)."""
        return {"min": [float(v) for v in self.lo], "max": [float(v) for v in self.hi],
                "counts": [int(c) for c in self.counts]}


MAX_PROBES_PER_AXIS = 32   # 32^3 probes keep their atlases (three copies) near 300 MiB


def parse_counts(value, where: str) -> tuple[int, int, int]:
    """Probes per axis: three integers from 1 to MAX_PROBES_PER_AXIS (or one for all three)."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        value = [int(value)] * 3
    try:
        counts = tuple(int(c) for c in value)
        ok = len(counts) == 3 and all(1 <= c <= MAX_PROBES_PER_AXIS and c == v for c, v in zip(counts, value))
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise OptionError(f"{where}: expected three probe counts (x, y, z), each 1 to {MAX_PROBES_PER_AXIS}, "
                          f"e.g. [8, 8, 8], got {value!r}")
    return counts


def volume_from_dict(d, where: str) -> ProbeVolume:
    """A user-placed volume: {"min": [x, y, z], "max": [x, y, z], "counts": [nx, ny, nz]} (world)."""
    if not isinstance(d, dict) or set(d) - {"min", "max", "counts"} or not {"min", "max"} <= set(d):
        raise OptionError(f"{where}: expected {{\"min\": [x, y, z], \"max\": [x, y, z], \"counts\": [nx, ny, nz]}} "
                          f"(world metres), got {d!r}")
    try:
        lo = np.asarray(d["min"], np.float64).reshape(3)
        hi = np.asarray(d["max"], np.float64).reshape(3)
    except (TypeError, ValueError):
        raise OptionError(f"{where}: min and max must be three numbers each") from None
    if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (hi > lo).all()):
        raise OptionError(f"{where}: max must exceed min on every axis (finite), got min {lo.tolist()} "
                          f"max {hi.tolist()}")
    return ProbeVolume(tuple(lo), tuple(hi), parse_counts(d.get("counts", [8, 8, 8]), f"{where}.counts"))


def volume_over_bounds(bounds, counts) -> ProbeVolume:
    """One volume over a scene's bounds ((2, 3) world AABB); an axis thinner than a tenth of the
    largest extent is widened to it, so a flat scene's probes do not sit on its surface."""
    lo, hi = (np.asarray(b, np.float64) for b in bounds)
    extent = np.maximum(hi - lo, 0.0)
    least = max(float(extent.max()) * 0.1, 1e-3)
    grow = np.maximum(least - extent, 0.0) * 0.5
    return ProbeVolume(tuple(lo - grow), tuple(hi + grow), tuple(int(c) for c in counts))


@dataclasses.dataclass(frozen=True)
class Atlas:
    """The tile layout of `probes` probes: `columns` tiles per row, `rows` rows."""

    probes: int
    columns: int
    rows: int

    @classmethod
    def for_probes(cls, probes: int) -> "Atlas":
        columns = max(1, math.ceil(math.sqrt(probes)))
        return cls(int(probes), columns, max(1, math.ceil(probes / columns)))

    def size(self, tile: int) -> tuple[int, int]:
        """(width, height) in texels of an atlas with `tile`-texel tiles."""
        return self.columns * tile, self.rows * tile

    def tile(self, probe: int) -> tuple[int, int]:
        return probe % self.columns, probe // self.columns


def pack_volumes(volumes: list[ProbeVolume], atlas: Atlas, origin, normal_bias: float, view_bias: float,
                 visibility: bool) -> bytes:
    """The ProbeVolumes storage block (glsl/probe_gi.glsl) in render space (world minus `origin`):
    uvec4 (volumes, atlas columns, probes, flags), then per volume origin.xyz + normal bias,
    spacing.xyz + view bias, counts.xyz + first probe, the box served (lo.xyz + max depth, hi)."""
    origin = np.zeros(3) if origin is None else np.asarray(origin, np.float64)
    head = np.array([len(volumes), atlas.columns, atlas.probes, FLAG_VISIBILITY if visibility else 0], np.uint32)
    rows, first = PROBE_VOLUME.zeros(len(volumes)), 0
    for row, v in zip(rows, volumes):
        spacing = v.spacing
        least = float(spacing.min())
        row["origin"] = (*(v.first_probe_position - origin), normal_bias * least)
        row["spacing"] = (*spacing, view_bias * least)
        row["counts"] = (*v.counts, first)
        # the depth limit: hits' depths stop here, misses record twice it (probe_gi.glsl PROBE_MISS_DEPTH)
        row["lo"] = (*(np.asarray(v.lo) - origin), 1.5 * float(np.linalg.norm(spacing)))
        row["hi"][:3] = np.asarray(v.hi) - origin
        first += v.probe_count
    return head.tobytes() + rows.tobytes()


def volume_bytes(count: int) -> int:
    return VOLUME_HEADER_BYTES + VOLUME_BYTES * max(1, count)


def random_rotation(seed) -> np.ndarray:
    """A uniformly distributed 3x3 rotation (Shoemake's quaternion), the same for the same seed."""
    u1, u2, u3 = np.random.default_rng(seed).random(3)
    a, b = math.sqrt(1 - u1), math.sqrt(u1)
    x, y, z, w = a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2), \
        b * math.sin(2 * math.pi * u3), b * math.cos(2 * math.pi * u3)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


# -- decoding readbacks (tests, benchmarks) -------------------------------------------------------
def oct_encode(d) -> np.ndarray:
    """Unit directions (..., 3) -> octahedral coordinates in [-1, 1]^2 (octahedral.glsl oct_encode)."""
    d = np.asarray(d, np.float64)
    p = d[..., :2] / np.abs(d).sum(axis=-1, keepdims=True)
    sign = np.where(p >= 0.0, 1.0, -1.0)
    folded = (1.0 - np.abs(p[..., ::-1])) * sign
    return np.where(d[..., 2:3] < 0.0, folded, p)


def sample_tile(atlas_texels: np.ndarray, atlas: Atlas, probe: int, direction, tile: int) -> np.ndarray:
    """Bilinear lookup of `direction` in probe `probe`'s tile of a read-back atlas
    (rows bottom-up, (h, w, c)), as the GLSL samples it."""
    tx, ty = atlas.tile(probe)
    e = oct_encode(np.asarray(direction, np.float64))
    inner = tile - 2
    x = tx * tile + 1 + (e[0] * 0.5 + 0.5) * inner - 0.5
    y = ty * tile + 1 + (e[1] * 0.5 + 0.5) * inner - 0.5
    x0, y0 = int(math.floor(x)), int(math.floor(y))
    fx, fy = x - x0, y - y0
    t = atlas_texels.astype(np.float64)
    return ((1 - fx) * (1 - fy) * t[y0, x0] + fx * (1 - fy) * t[y0, x0 + 1]
            + (1 - fx) * fy * t[y0 + 1, x0] + fx * fy * t[y0 + 1, x0 + 1])


def tiles(atlas_texels: np.ndarray, atlas: Atlas, tile: int) -> np.ndarray:
    """The atlas (h, w, c) as (probes, tile, tile, c)."""
    h, w, c = atlas_texels.shape
    t = atlas_texels.reshape(atlas.rows, tile, atlas.columns, tile, c).transpose(0, 2, 1, 3, 4)
    return t.reshape(atlas.rows * atlas.columns, tile, tile, c)[:atlas.probes]
