"""A configuration's bias floor: its own converged image against the reference.

However many frames a configuration averages, its error cannot fall below the light it leaves
out (fewer bounces, no indirect light, shadows without rays...). The floor renders the
configuration itself for many frames from its own seed range (rayvr.study.seeds), each frame's
output averaged (its Accumulate passes pass single frames through), as two halves like the
reference. Against the reference:

    relmse        relMSE(floor image, reference)
    noise_relmse  what noise alone would give: the floor's predicted relMSE (its halves) plus the
                  reference's
    bias_relmse   relmse - noise_relmse (at least 0): the light the configuration leaves out

A configuration with the reference's own settings has `relmse` within its noise (`within_noise`:
relmse <= 2 noise_relmse); one that drops bounces does not. Floors cost as much as a reference
and are cached the same way.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from pathlib import Path

import numpy as np

from . import seeds
from .configs import effects_restored
from .reference import code_digest, default_cache_dir, load_halves, scene_digest, store_halves, views_digest


@dataclasses.dataclass
class Floor:
    """A configuration's converged image (mean of halves A and B) and where it came from."""

    name: str
    image: np.ndarray
    half_a: np.ndarray
    half_b: np.ndarray
    frames: int
    first_frame: int
    seconds: float
    source: str

    def noise_relmse(self, eps: float) -> float:
        """The floor image's predicted relMSE against its own expectation (halves)."""
        a, b, m = (x[..., :3].astype(np.float64) for x in (self.half_a, self.half_b, self.image))
        return float(((a - b) ** 2 / 4.0 / (m * m + eps)).mean())

    def against(self, reference) -> dict:
        """relmse, noise_relmse, bias_relmse and within_noise against `reference` (module docstring)."""
        from .metrics import rel_mse

        eps = reference.eps
        relmse = rel_mse(self.image, reference.image, eps, names=(f"floor of '{self.name}'", reference.name))
        noise = self.noise_relmse(eps) + reference.noise_relmse
        return {"relmse": relmse, "noise_relmse": noise, "bias_relmse": max(0.0, relmse - noise),
                "within_noise": bool(relmse <= 2.0 * noise), "frames": self.frames,
                "seeds": {"first_frame": self.first_frame}, "seconds": self.seconds, "source": self.source}


def even_frames(frames: int) -> int:
    """Frames rounded up to an even count >= 2 (two equal halves)."""
    return max(2, int(frames) + int(frames) % 2)


def floor_key(scene, view_set, config, frames: int) -> str:
    text = json.dumps([code_digest(), "floor", scene_digest(scene), views_digest(view_set), config.key(scene), frames])
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def render_floor(scene, config, view_set, frames: int, gpu=None, tick=None) -> Floor:
    """Render `config` converged over `frames` frames (even) from its own seed range."""
    from .progressive import render_mean, split_halves

    frames = even_frames(frames)
    first = seeds.floor_first_frame(config.key(scene))
    t0 = time.perf_counter()
    with effects_restored(scene):
        config.apply(scene)
        graph = config.build_graph()
        shots = render_mean(scene, graph, config.output_pin(graph), view_set, frames, first,
                            snapshots=(frames // 2,), gpu=gpu, tick=tick)
    a, b = split_halves(shots[0].image, shots[-1].image)
    return Floor(config.name, shots[-1].image, a, b, frames, first, time.perf_counter() - t0, "rendered")


def bias_floor(scene, config, view_set, frames: int, cache_dir=None, gpu=None, tick=None) -> Floor:
    """`render_floor`, cached like the reference (`cache_dir=False`: no cache)."""
    frames = even_frames(frames)
    if cache_dir is False:
        return render_floor(scene, config, view_set, frames, gpu, tick)
    floor = load_floor(scene, config, view_set, frames, cache_dir)
    if floor is None:
        floor = render_floor(scene, config, view_set, frames, gpu, tick)
        store_floor(scene, config, view_set, floor, cache_dir)
    return floor


def load_floor(scene, config, view_set, frames: int, cache_dir=None) -> Floor | None:
    """The cached floor of `config` over `frames` frames, or None when it is not in the cache."""
    path = floor_path(scene, config, view_set, even_frames(frames), cache_dir)
    cached = load_halves(path)
    if cached is None:
        return None
    image, a, b, meta = cached
    return Floor(config.name, image, a, b, int(meta["frames"]), int(meta["first_frame"]), 0.0, str(path))


def store_floor(scene, config, view_set, floor: Floor, cache_dir=None) -> None:
    """Put a rendered floor into the cache (atomically); its `source` becomes the cache file."""
    path = floor_path(scene, config, view_set, floor.frames, cache_dir)
    store_halves(path, floor.image, floor.half_a, {"config": config.name, "frames": floor.frames,
                                                    "first_frame": floor.first_frame, "seconds": floor.seconds})
    floor.source = str(path)


def floor_path(scene, config, view_set, frames: int, cache_dir=None) -> Path:
    folder = Path(cache_dir) if cache_dir else default_cache_dir()
    return folder / f"floor-{scene.name}-{floor_key(scene, view_set, config, frames)}.npz"
