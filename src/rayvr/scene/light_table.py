"""Every light of a scene in one table, sampled by power through an alias table (Walker 1977,
Vose's construction): O(1) per sample whatever the number of lights.

Powers (watts up to a common constant; only ratios matter):
- point light: 4 pi I (I: luminance of colour x intensity, candela);
- spot light: 2 pi I (1 - (cos inner + cos outer) / 2), its cone as glTF's smooth falloff spans it;
- directional light: E pi R^2 (E lux on the disc of the scene's bounding sphere, radius R);
- emissive triangle: pi L A (x 2 when double-sided), L the luminance of its emission (the
  material factor: textures are not in the power), A its world-space area in float64;
- environment: 4 pi^2 R^2 L_mean (pbrt's infinite light), L_mean its mean luminance over the
  sphere.

The GPU side (glsl/lights.glsl) picks entry k with probability power_k / total, then a point or
direction within it. An emissive triangle's selection probability over its area is
L / (pi total) x (pi, or 2 pi double-sided) — its area cancels — so the pdf of a point on a
light never needs the area recomputed (in float32, from render-space vertices).

Spatial selection (Scene.light_selection "spatial"; `pack_clusters`, `pack_emissive`): each instance
with emissive triangles is an emissive *cluster* (a bounding sphere, its power and an alias table
over its own triangles). In a scene
of at most LOCAL_PUNCTUAL_MAX punctual lights and EMISSIVE_CLUSTERS_MAX clusters the GPU draws,
below the environment's share, between the punctual lights and each cluster by an estimate of
the irradiance each gives the shading point: I / d^2 (cone and range included) for a punctual
light, power / (pi max(d^2, r^2)) for a cluster of radius r at distance d. A wall beside a small
lamp then spends a fair share of its samples on the lamp instead of the global power's few per
cent (tauray/test.glb: 4%, each a firefly 24 times the mean).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..gpu.records import LIGHT_ENTRY

POINT, SPOT, DIRECTIONAL = 0, 1, 2
KIND_PUNCTUAL, KIND_EMISSIVE, KIND_ENVIRONMENT = 0, 1, 2
EMISSIVE_CLUSTERS_MAX = 16   # as glsl/lights.glsl: more emissive instances fall back to the table


def luminance(rgb) -> np.ndarray:
    rgb = np.asarray(rgb, dtype=np.float64)
    return rgb[..., 0] * 0.2126 + rgb[..., 1] * 0.7152 + rgb[..., 2] * 0.0722


def alias_table(weights) -> tuple[np.ndarray, np.ndarray]:
    """(threshold, alias) of Vose's alias method for `weights` (>= 0, not all 0): draw k uniform
    in [0, n) and x in [0, 1); take k if x < threshold[k], else alias[k]. Entry k is drawn with
    probability weights[k] / sum."""
    w = np.asarray(weights, dtype=np.float64)
    n = len(w)
    scaled = w * (n / w.sum())
    threshold = np.ones(n)
    alias = np.arange(n, dtype=np.int64)
    small = [i for i in range(n) if scaled[i] < 1.0]
    large = [i for i in range(n) if scaled[i] >= 1.0]
    while small and large:
        s, g = small.pop(), large[-1]
        threshold[s], alias[s] = scaled[s], g
        scaled[g] -= 1.0 - scaled[s]
        if scaled[g] < 1.0:
            large.pop()
            small.append(g)
    return threshold, alias   # left-over entries (rounding) keep threshold 1: themselves


def alias_probabilities(threshold: np.ndarray, alias: np.ndarray) -> np.ndarray:
    """The probability of each entry under an alias table (for tests: it must equal weights / sum)."""
    n = len(threshold)
    p = threshold / n
    np.add.at(p, alias, (1.0 - threshold) / n)
    return p


def punctual_powers(lights, scene_radius: float) -> np.ndarray:
    """Power of each KHR_lights_punctual light (see the module docstring)."""
    out = np.zeros(len(lights))
    for k, L in enumerate(lights):
        i = float(luminance(L.color)) * float(L.intensity)
        if L.type == DIRECTIONAL:
            out[k] = i * math.pi * scene_radius ** 2
        elif L.type == SPOT:
            out[k] = 2 * math.pi * i * (1.0 - 0.5 * (math.cos(L.inner_cone_angle) + math.cos(L.outer_cone_angle)))
        else:
            out[k] = 4 * math.pi * i
    return np.maximum(out, 0.0)


def environment_power(environment, scene_radius: float) -> float:
    """Power of the environment as the scene receives it (pbrt's 4 pi^2 R^2 L_mean)."""
    if environment is None:
        return 0.0
    mean = float(luminance(environment.color))
    if environment.image is not None:
        h = environment.image.shape[0]
        sin_theta = np.sin((np.arange(h) + 0.5) / h * math.pi)
        lum = luminance(environment.image)
        mean *= float((lum * sin_theta[:, None]).sum() / (sin_theta.sum() * environment.image.shape[1]))
    return 4 * math.pi ** 2 * scene_radius ** 2 * mean


@dataclasses.dataclass
class LightTable:
    """The alias table over every light: kind (punctual, emissive triangle, environment), the
    index within its kind, selection probability, and the alias pair."""

    kinds: np.ndarray          # (n,) KIND_*
    indices: np.ndarray        # (n,) index within the kind's own buffer
    probabilities: np.ndarray  # (n,) power / total
    threshold: np.ndarray
    alias: np.ndarray
    total_power: float

    @property
    def count(self) -> int:
        return len(self.kinds)

    def probability_of(self, kind: int) -> float:
        """Summed selection probability of one kind (e.g. the environment's)."""
        return float(self.probabilities[self.kinds == kind].sum())

    def packed(self) -> np.ndarray:
        """The SSBO of glsl/lights.glsl as float32 rows of 4: header vec4 (count bits, total power,
        environment probability, 1 / total), then a `records.LIGHT_ENTRY` per entry (one zeroed
        entry for an empty table)."""
        header = np.zeros(4, np.float32)   # vec4 light_table_info
        header.view(np.uint32)[0] = self.count
        header[1] = self.total_power
        header[2] = self.probability_of(KIND_ENVIRONMENT)
        header[3] = 1.0 / self.total_power if self.total_power > 0 else 0.0
        entries = LIGHT_ENTRY.zeros(max(self.count, 1))
        n = self.count
        entries["ids"][:n, 0], entries["ids"][:n, 1], entries["ids"][:n, 2] = self.kinds, self.indices, self.alias
        entries["select"][:n, 0], entries["select"][:n, 1] = self.threshold, self.probabilities
        entries["select"][:n, 2] = np.where(self.kinds == KIND_PUNCTUAL, self.probability_of(KIND_PUNCTUAL), 0.0)
        return np.concatenate([header, entries.view(np.float32)]).reshape(-1, 4)


def build_light_table(punctual: np.ndarray, emissive: np.ndarray, environment: float) -> LightTable:
    """The table over punctual lights, emissive triangles and the environment, by their powers
    (entries of power 0 are left out)."""
    kinds = np.concatenate([np.full(len(punctual), KIND_PUNCTUAL), np.full(len(emissive), KIND_EMISSIVE),
                            np.full(1 if environment > 0 else 0, KIND_ENVIRONMENT)]).astype(np.uint32)
    indices = np.concatenate([np.arange(len(punctual)), np.arange(len(emissive)),
                              np.zeros(1 if environment > 0 else 0)]).astype(np.uint32)
    power = np.concatenate([punctual, emissive, [environment] if environment > 0 else []]).astype(np.float64)
    keep = power > 0
    kinds, indices, power = kinds[keep], indices[keep], power[keep]
    total = float(power.sum())
    if not len(power):
        return LightTable(kinds, indices, power, np.ones(0), np.zeros(0, np.int64), 0.0)
    threshold, alias = alias_table(power)
    return LightTable(kinds, indices, power / total, threshold, alias, total)


@dataclasses.dataclass
class EmissiveCluster:
    """The emissive triangles of one instance: entries [first, first + count) of the emissive
    list, the bounding sphere of their object-space vertices and their summed power."""

    instance: int
    centre: np.ndarray    # object space
    radius: float         # object space
    first: int
    count: int
    power: float


def emissive_cluster(instance: int, triangles: np.ndarray, first: int, powers: np.ndarray) -> EmissiveCluster:
    """The cluster of `instance`'s emissive triangles ((k, 3, 3) object space) and their powers,
    starting at emissive entry `first`."""
    v = np.asarray(triangles, np.float64).reshape(-1, 3)
    centre = 0.5 * (v.min(axis=0) + v.max(axis=0))
    radius = float(np.linalg.norm(v - centre, axis=1).max())
    return EmissiveCluster(int(instance), centre, radius, int(first), len(powers), float(np.sum(powers)))


CLUSTER_ROWS = 1 + 2 * EMISSIVE_CLUSTERS_MAX   # the header and the cluster rows of pack_emissive


def drawn_clusters(clusters: list[EmissiveCluster], spatial: bool) -> int:
    """How many clusters the spatial selection draws among: all of them, or 0 (selection by power)
    when it is off or there are more than EMISSIVE_CLUSTERS_MAX."""
    return len(clusters) if spatial and len(clusters) <= EMISSIVE_CLUSTERS_MAX else 0


def pack_clusters(clusters: list[EmissiveCluster], transforms: np.ndarray, anchor, spatial: bool = True) -> np.ndarray:
    """The head of the EmissiveTriangles block (glsl/lights.glsl), CLUSTER_ROWS vec4 rows: uvec4
    (cluster count: 0 when there are more than EMISSIVE_CLUSTERS_MAX or not `spatial`, then the
    table alone draws), then per cluster vec4 (anchor-space centre: the instance's transform minus
    `anchor`; world radius: scaled by the transform's largest axis scale) and uvec4 (instance,
    first entry, entry count, power bits). Rewritten whenever instances move or the anchor does."""
    out = np.zeros((CLUSTER_ROWS, 4), np.float32)
    if not drawn_clusters(clusters, spatial):
        return out
    bits = out.view(np.uint32)
    bits[0, 0] = len(clusters)
    anchor = np.asarray(anchor, np.float64)
    for k, c in enumerate(clusters):
        t = np.asarray(transforms[c.instance], np.float64)
        out[1 + 2 * k, 0:3] = t[:3, :3] @ c.centre + t[:3, 3] - anchor
        out[1 + 2 * k, 3] = c.radius * float(np.linalg.norm(t[:3, :3], axis=0).max())
        bits[2 + 2 * k, 0:3] = c.instance, c.first, c.count
        out[2 + 2 * k, 3] = c.power
    return out


def pack_emissive(ids: np.ndarray, powers: np.ndarray, clusters: list[EmissiveCluster],
                  head: np.ndarray | None) -> np.ndarray:
    """The EmissiveTriangles block. Selection by power (`head` None): per triangle uvec4 (instance,
    mesh-local triangle, material, -). Spatial: `head` (pack_clusters), then per triangle uvec4
    (instance, mesh-local triangle, material, alias entry within its cluster) and vec4 (alias
    threshold, -, -, -); float32 rows with uint fields as bits."""
    if head is None:
        return np.ascontiguousarray(ids, np.uint32)
    n = len(powers)
    out = np.zeros((CLUSTER_ROWS + 2 * n, 4), np.float32)
    out[:CLUSTER_ROWS] = head
    bits = out.view(np.uint32)
    rows = CLUSTER_ROWS + 2 * np.arange(n)
    bits[rows] = ids
    for c in clusters:
        threshold, alias = alias_table(powers[c.first:c.first + c.count])
        bits[rows[c.first:c.first + c.count], 3] = alias + c.first
        out[rows[c.first:c.first + c.count] + 1, 0] = threshold
    return out
