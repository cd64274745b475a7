"""The scene's ground truth for the error study: a converged, checked, cached path-traced render.

The reference path traces every pixel from the camera (PathTracer "full" mode + Accumulate,
paths starting at pixel centres as the raster G-buffer samples them) for `frames` frames of `spp`
paths each, from its own seed range (rayvr.tune.seeds), as two halves A and B of frames/2 frames
each. Its image is their mean. Two checks say whether it can be trusted:

- **converged**: the halves are independent estimates, so (A - B)^2 / 4 estimates per pixel the
  squared error of the mean. Its relMSE-weighted mean, mean((A - B)^2 / 4 / (M^2 + eps)), is the
  mean's predicted relMSE against the truth. It must be below `tolerance` (default 5e-4: an RMS
  error of ~2% of each pixel's radiance, a tenth or less of the relMSE of the 16-spp
  configurations it judges on the Cornell box).
- **enough bounces**: B + 1 bounces rendered over half A's first `check_frames` frames with half
  A's random numbers (so the two differ only by the extra bounce's light) change the mean
  radiance by less than `bounce_tolerance` (default 1%).

The cache is an .npz per (scene content, views, size, settings, seed range, rayvr's version and
shaders) in
`cache_dir` (default $XDG_CACHE_HOME/rayvr/references, else ~/.cache/rayvr/references), written
under a temporary name and renamed, so an interrupted render never leaves a half-written one.
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import os
from pathlib import Path

import numpy as np

from ..errors import OptionError
from ..fileio import atomic_write
from . import seeds
from .display import LUMINANCE

CACHE_VERSION = 3          # bump when a change outside the shaders changes what a reference shows
SHADER_SUFFIXES = (".glsl", ".comp", ".vert", ".frag")
NAME = "path-traced reference"
PIN = "Accumulate.dst"     # the reference graph's running mean


@dataclasses.dataclass(frozen=True)
class ReferenceSettings:
    """How the reference is rendered and checked (see the module docstring)."""

    frames: int = 256
    spp: int = 16
    max_bounces: int = 8
    tolerance: float = 5e-4
    bounce_tolerance: float = 0.01
    check_frames: int | None = None      # bounce check frames; default frames // 4

    def __post_init__(self):
        for key in ("frames", "spp", "max_bounces"):
            value = getattr(self, key)
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise OptionError(f"reference {key}: must be an integer >= 1, got {value!r}")
        if self.frames < 2 or self.frames % 2:
            raise OptionError(f"reference frames: {self.frames} cannot be split into two equal halves; "
                              f"give an even number >= 2")
        for key in ("tolerance", "bounce_tolerance"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and value > 0 and math.isfinite(value)):
                raise OptionError(f"reference {key}: must be a number > 0, got {value!r}")
        if self.check_frames is not None and not 1 <= self.check_frames <= self.frames // 2:
            raise OptionError(f"reference check_frames: must be 1..{self.frames // 2} (half A's frames), "
                              f"got {self.check_frames}")
        seeds.check_length(self.frames, "reference frames")

    @property
    def samples_per_pixel(self) -> int:
        """Paths per pixel of the whole reference."""
        return self.frames * self.spp

    @property
    def bounce_check_frames(self) -> int:
        return self.check_frames or max(1, self.frames // 4)

    def as_dict(self) -> dict:
        return {"frames": self.frames, "spp_per_frame": self.spp, "samples_per_pixel": self.samples_per_pixel,
                "bounces": self.max_bounces, "tolerance_relmse": self.tolerance,
                "bounce_tolerance": self.bounce_tolerance, "bounce_check_frames": self.bounce_check_frames}


@dataclasses.dataclass
class Reference:
    """A rendered reference: its image (the mean of halves A and B), the halves, the checks."""

    image: np.ndarray           # (views, h, w, 4) float32 linear radiance, row 0 at the top
    half_a: np.ndarray
    half_b: np.ndarray
    settings: ReferenceSettings
    first_frame: int
    bounce_change: float        # relative change of the mean radiance with one more bounce
    seconds: float              # wall seconds its render took (0 when loaded from the cache)
    source: str                 # "rendered" or the cache file
    eps: float = 1e-2
    name: str = NAME

    @property
    def noise_relmse(self) -> float:
        """The mean's predicted relMSE against the truth: mean((A - B)^2 / 4 / (M^2 + eps))."""
        return float(self.noise_map().mean())

    def noise_map(self) -> np.ndarray:
        """Per pixel (views, h, w): the predicted relative squared error of the mean."""
        a, b, m = (x[..., :3].astype(np.float64) for x in (self.half_a, self.half_b, self.image))
        return ((a - b) ** 2 / 4.0 / (m * m + self.eps)).mean(axis=-1)

    @property
    def converged(self) -> bool:
        return self.noise_relmse <= self.settings.tolerance

    @property
    def bounces_enough(self) -> bool:
        return abs(self.bounce_change) <= self.settings.bounce_tolerance

    def frames_to_converge(self) -> int:
        """Frames (of `settings.spp` paths) that would bring the predicted relMSE to the
        tolerance (noise falls as 1 / frames), rounded up to an even count."""
        need = self.settings.frames * self.noise_relmse / self.settings.tolerance
        return max(2, 2 * math.ceil(need / 2))

    @property
    def halves_identical(self) -> bool:
        """Whether A and B are equal to the bit: light without noise at these settings (one point
        light, direct light only), or a half that was never added (a GPU has given that)."""
        return bool(np.array_equal(self.half_a[..., :3], self.half_b[..., :3]))

    def verdict(self) -> str:
        """One line: converged or not, and whether the bounces suffice."""
        s = self.settings
        noise = (f"converged: halves predict relMSE {self.noise_relmse:.2e} <= tolerance {s.tolerance:.0e}"
                 if self.converged else
                 f"NOT converged: halves predict relMSE {self.noise_relmse:.2e} > tolerance {s.tolerance:.0e} "
                 f"(about {self.frames_to_converge()} frames of {s.spp} spp would do)")
        if self.halves_identical:
            noise = ("halves identical (noise-free light at these settings, or a half that was not rendered: the "
                     "convergence check cannot tell)")
        bounce = (f"{s.max_bounces} bounces: one more changes the mean radiance by {100 * self.bounce_change:+.2f}% "
                  f"({'within' if self.bounces_enough else 'OVER'} the {100 * s.bounce_tolerance:g}% tolerance)")
        return f"{noise}; {bounce}"

    def as_dict(self) -> dict:
        return {"name": self.name, "settings": self.settings.as_dict(),
                "seeds": {"first_frame": self.first_frame,
                          "half_a_frames": [self.first_frame, self.first_frame + self.settings.frames // 2],
                          "half_b_frames": [self.first_frame + self.settings.frames // 2,
                                            self.first_frame + self.settings.frames]},
                "convergence": {"verdict": "halves identical" if self.halves_identical else
                                ("converged" if self.converged else "not converged"),
                                "predicted_relmse": self.noise_relmse, "tolerance": self.settings.tolerance,
                                "eps": self.eps, "method": "halves A, B: mean((A-B)^2/4 / (M^2+eps))"},
                "bounces": {"bounces": self.settings.max_bounces, "relative_change_one_more": self.bounce_change,
                            "tolerance": self.settings.bounce_tolerance,
                            "verdict": "enough" if self.bounces_enough else "too few"},
                "seconds": self.seconds, "source": self.source}


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


def reference_graph(settings: ReferenceSettings, bounces: int | None = None):
    """The reference's render graph: `settings.spp` paths per pixel per frame, accumulated."""
    from .configs import path_traced_graph

    return path_traced_graph(spp=settings.spp, max_bounces=bounces or settings.max_bounces)


@functools.cache
def code_digest() -> str:
    """A hash of rayvr's version and every shader it ships: a cached reference or floor rendered
    by other GPU code is not reused (CACHE_VERSION covers changes outside the shaders)."""
    from .. import __version__

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(f"{__version__} {CACHE_VERSION}".encode())
    for path in sorted(p for p in root.rglob("*") if p.suffix in SHADER_SUFFIXES):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def reference_key(scene, view_set, settings: ReferenceSettings, first_frame: int) -> str:
    """The cache key: everything that changes the reference (scene content, views, size,
    settings, the path tracer's properties, the seed range, the code: code_digest)."""
    tracer = reference_graph(settings).get_pass("PathTracer").get_properties()
    text = json.dumps([code_digest(), scene_digest(scene), views_digest(view_set), dataclasses.asdict(settings),
                       first_frame, tracer], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def render_reference(scene, view_set, settings: ReferenceSettings = ReferenceSettings(), first_frame: int | None = None,
                     gpu=None, tick=None, eps: float = 1e-2) -> Reference:
    """Render the reference and its checks (see the module docstring). `tick(frames)` is told
    how many frames have been rendered (of settings.frames + the bounce check's)."""
    import time

    from .progressive import render_mean, split_halves

    first = seeds.reference_first_frame() if first_frame is None else int(first_frame)
    half, check = settings.frames // 2, settings.bounce_check_frames
    t0 = time.perf_counter()
    # each half its own render (frames [first, first + half) and [first + half, first + frames))
    shots = render_mean(scene, reference_graph(settings), PIN, view_set, half, first, snapshots=(check,), gpu=gpu,
                        tick=tick)
    a, at_check = shots[-1].image, next(s.image for s in shots if s.frames == check)
    b = render_mean(scene, reference_graph(settings), PIN, view_set, half, first + half, gpu=gpu,
                    tick=None if tick is None else (lambda n: tick(half + n)))[-1].image
    image = ((a.astype(np.float64) + b) * 0.5).astype(np.float32)
    a, b = split_halves(a, image)    # B as the cache gives it back (2 image - A, in float32)
    more = render_mean(scene, reference_graph(settings, settings.max_bounces + 1), PIN, view_set,
                       check, first, gpu=gpu,
                       tick=None if tick is None else (lambda n: tick(settings.frames + n)))[-1].image
    change = relative_change(more, at_check)
    return Reference(image, a, b, settings, first, change, time.perf_counter() - t0, "rendered", eps)


def relative_change(image: np.ndarray, base: np.ndarray) -> float:
    """(mean luminance of image - that of base) / that of base; 0 when both are black."""
    lum = float((base[..., :3].astype(np.float64) @ LUMINANCE).mean())
    more = float((image[..., :3].astype(np.float64) @ LUMINANCE).mean())
    return 0.0 if lum == 0.0 and more == 0.0 else (more - lum) / max(lum, 1e-30)


def cached_reference(scene, view_set, settings: ReferenceSettings = ReferenceSettings(), cache_dir=None, gpu=None,
                     tick=None, sample: int = 0, eps: float = 1e-2, render=None) -> Reference:
    """The reference of `scene` seen by `view_set`: from the cache when there, else rendered
    and stored (`cache_dir=False` disables the cache). `sample` picks the seed range (0 for the
    static view, k for trajectory sample k). `render(first_frame) -> Reference` renders a
    missing one (default: `render_reference` on `gpu`; rayvr.cluster splits it over workers)."""
    first = seeds.reference_first_frame(sample)
    if render is None:
        def render(first_frame: int) -> Reference:
            return render_reference(scene, view_set, settings, first_frame, gpu, tick, eps)
    if cache_dir is False:
        return render(first)
    path = cache_path(scene, view_set, settings, first, cache_dir)
    cached = load_halves(path)
    if cached is not None:
        image, a, b, meta = cached
        return Reference(image, a, b, settings, first, float(meta["bounce_change"]), 0.0, str(path), eps)
    ref = render(first)
    store_halves(path, ref.image, ref.half_a, {"scene": scene.name, "views": len(view_set),
                                               "size": list(view_set.size), "first_frame": first,
                                               "bounce_change": ref.bounce_change, "seconds": ref.seconds,
                                               **dataclasses.asdict(settings)})
    ref.source = str(path)
    return ref


def load_halves(path: Path):
    """(image, half A, half B, meta) from a cache file, or None when it is missing or damaged
    (then the caller renders again and replaces it)."""
    if not path.exists():
        return None
    from .progressive import split_halves

    try:
        with np.load(path) as data:
            meta = json.loads(str(data["meta"]))
            image, a = data["image"], data["half_a"]
    except (OSError, ValueError, KeyError):
        return None
    return (image, *split_halves(a, image), meta)


def store_halves(path: Path, image: np.ndarray, half_a: np.ndarray, meta: dict) -> None:
    """Write a mean and its first half (the second is derived) with `meta`, atomically.
    Uncompressed: radiance compresses by ~10%, and zlib took 6.5 s of the study's own process per
    2x1440x1600 image pair (0.5 s plain), a floor's whole GPU time many times over."""
    text = json.dumps(meta)
    atomic_write(path, lambda tmp: np.savez(tmp, image=image, half_a=half_a, meta=np.array(text)))


def cache_path(scene, view_set, settings, first_frame: int, cache_dir=None) -> Path:
    """Where the reference's cache file lives."""
    folder = Path(cache_dir) if cache_dir else default_cache_dir()
    return folder / (f"{scene.name}-{len(view_set)}x{view_set.size[0]}x{view_set.size[1]}-"
                     f"{reference_key(scene, view_set, settings, first_frame)}.npz")


def is_cached(scene, view_set, settings, cache_dir=None, sample: int = 0) -> bool:
    """Whether the reference is in the cache (the study's progress estimate skips its cost)."""
    return cache_dir is not False and cache_path(scene, view_set, settings, seeds.reference_first_frame(sample),
                                                 cache_dir).exists()
