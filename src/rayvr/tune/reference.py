"""Converged reference images: a long PathTracer + Accumulate render of every pixel, cached.

The cache is an .npz per (scene content, views, size, settings) in `cache_dir` (default
$XDG_CACHE_HOME/rayvr/references, else ~/.cache/rayvr/references), written under a temporary
name and renamed, so an interrupted render never leaves a half-written reference.
Paths start at pixel centres (no jitter), as the raster G-buffer samples pixels, so edges do
not count as error for every configuration.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..errors import OptionError
from ..fileio import atomic_write

CACHE_VERSION = 1


@dataclasses.dataclass(frozen=True)
class ReferenceSettings:
    """How the reference is rendered: `frames` x `spp` paths per pixel of up to `max_bounces`."""

    frames: int = 256
    spp: int = 4
    max_bounces: int = 8

    def __post_init__(self):
        for key in ("frames", "spp", "max_bounces"):
            value = getattr(self, key)
            if int(value) != value or value < 1:
                raise OptionError(f"reference {key}: must be an integer >= 1, got {value!r}")


def default_cache_dir() -> Path:
    """$XDG_CACHE_HOME/rayvr/references, else ~/.cache/rayvr/references."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "rayvr" / "references"


def scene_digest(scene) -> str:
    """A hash of what the image depends on: geometry, placements, materials (but not their
    effect ids: the reference path traces everything), lights, textures."""
    h = hashlib.sha256()
    for mesh in scene.meshes:
        for a in (mesh.positions, mesh.indices, mesh.material_ids, mesh.normals, mesh.uvs, mesh.tangents):
            h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
    for inst in scene.instances:
        h.update(np.int64(inst.mesh).tobytes() + np.ascontiguousarray(inst.transform).tobytes())
    for m in scene.materials:
        fields = {f.name: getattr(m, f.name) for f in dataclasses.fields(m) if f.name != "effect"}
        h.update(repr(sorted(fields.items())).encode())
    for light in scene.lights:
        h.update(repr(sorted(vars(light).items())).encode())
    for tex in getattr(scene, "textures", []):
        h.update(np.ascontiguousarray(tex.image).tobytes() + repr(tex.srgb).encode())
    return h.hexdigest()


def views_digest(view_set) -> str:
    """A hash of the views' origin, matrices (as float32, what the GPU sees), count and size."""
    m = view_set.matrices()
    h = hashlib.sha256(np.asarray(view_set.origin(), np.float64).tobytes())
    h.update(m["view"].astype(np.float32).tobytes() + m["proj"].astype(np.float32).tobytes())
    h.update(repr((len(view_set), tuple(view_set.size))).encode())
    return h.hexdigest()


def reference_key(scene, view_set, settings: ReferenceSettings) -> str:
    """The cache key: scene content + views + size + settings."""
    text = json.dumps([CACHE_VERSION, scene_digest(scene), views_digest(view_set), dataclasses.asdict(settings)])
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def render_reference(scene, view_set, settings: ReferenceSettings = ReferenceSettings(), gpu=None,
                     progress: bool = True) -> np.ndarray:
    """Path trace every pixel for `settings.frames` frames; (views, h, w, 4) float32 linear
    radiance, row 0 at the top."""
    from tqdm import tqdm

    from ..renderer import Renderer
    from .configs import path_traced_graph

    graph = path_traced_graph(spp=settings.spp, max_bounces=settings.max_bounces)
    with Renderer(scene, graph, views=view_set, gpu=gpu, profiling=False) as r:
        for _ in tqdm(range(settings.frames), desc=f"reference {scene.name}", unit="frame",
                      disable=not progress, leave=False):
            r.render()
        return r.read_output("Accumulate.dst", flip_y=True).astype(np.float32)


def reference_image(scene, view_set, settings: ReferenceSettings = ReferenceSettings(), cache_dir=None,
                    gpu=None, progress: bool = True) -> tuple[np.ndarray, Path | None]:
    """The converged reference of `scene` seen by `view_set` and its cache file: loaded from the
    cache when there, else rendered and stored (`cache_dir=False` disables the cache)."""
    if cache_dir is False:
        return render_reference(scene, view_set, settings, gpu, progress), None
    path = reference_path(scene, view_set, settings, cache_dir)
    image = cached_reference(path)
    if image is not None:
        return image, path
    image = render_reference(scene, view_set, settings, gpu, progress)
    store_reference(path, image, scene, view_set, settings)
    return image, path


def reference_path(scene, view_set, settings: ReferenceSettings, cache_dir=None) -> Path:
    """The cache file of this reference (in `cache_dir`, default `default_cache_dir()`)."""
    folder = Path(cache_dir) if cache_dir else default_cache_dir()
    return folder / f"{scene.name}-{len(view_set)}x{view_set.size[0]}x{view_set.size[1]}-" \
                    f"{reference_key(scene, view_set, settings)}.npz"


def cached_reference(path: Path) -> np.ndarray | None:
    """The image in cache file `path`, or None when it is missing or damaged."""
    if path.exists():
        try:
            with np.load(path) as data:
                return data["image"]
        except (OSError, ValueError, KeyError):
            pass   # a damaged cache file: render again and replace it
    return None


def store_reference(path: Path, image: np.ndarray, scene, view_set, settings: ReferenceSettings) -> Path:
    """Write a reference to cache file `path` atomically."""
    meta = json.dumps({"scene": scene.name, "views": len(view_set), "size": list(view_set.size),
                       **dataclasses.asdict(settings)})
    return atomic_write(path, lambda tmp: np.savez_compressed(tmp, image=image, meta=np.array(meta)))
