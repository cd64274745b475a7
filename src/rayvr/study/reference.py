"""The scene's ground truth for the error study: a converged, checked, cached path-traced render.

The reference path traces every pixel from the camera (PathTracer "full" mode + Accumulate) with
each path starting at a random point of its pixel: a box filter over the pixel's footprint, the
value a displayed pixel integrates, stratified over the frames by the Sobol sampler. Configurations
that do not anti-alias (the G-buffer samples pixel centres) show their aliasing as error against
it. It renders `frames` frames of `spp` paths from its own seed range (rayvr.study.seeds) as two
halves A and B of frames/2 frames each; its image is their mean. Two checks say whether it can be
trusted:

- **converged**: the halves are independent estimates, so (A - B)^2 / 4 estimates per pixel the
  squared error of the mean. Its relMSE-weighted mean, mean((A - B)^2 / 4 / (M^2 + eps)), is the
  mean's predicted relMSE against the truth. It must be below `tolerance` (default 5e-4: an RMS
  error of ~2% of each pixel's radiance, a tenth or less of the relMSE of the 16-spp
  configurations it judges on the Cornell box).
- **enough bounces**: B + 1 bounces rendered over half A's first `check_frames` frames with half
  A's random numbers (so the two differ only by the extra bounce's light) change the mean
  radiance by less than `bounce_tolerance` (default 1%).

**Rendered until converged** (`max_frames` > `frames`): while the halves predict more than the
tolerance, the reference renders on in extensions (`converge`): each appends the next frames of
its seed range, the first half of them to A and the second to B, sized by the halves' forecast
(at least `frames`, at most doubling what is there), until it converges, reaches `max_frames`,
or its rendering time, summed over every run that extended it, would pass `max_seconds`. The
reference is never clamped. Why it stopped is its `stop` ("converged", "frames cap", "time cap",
"fixed": `max_frames` not set).

The cache is an .npz per (scene content, views, size, spp, bounces, round size `frames`, seed
range, rayvr's version and shaders) in `cache_dir` (default $XDG_CACHE_HOME/rayvr/references,
else ~/.cache/rayvr/references), written under a temporary name and renamed after the first
round and after every extension, so an interrupted render never leaves a half-written one and a
later run resumes from the last extension. The caps and tolerances are not in the key: a run with
a larger cap extends the cached reference.
"""
from __future__ import annotations

import contextlib
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

CACHE_VERSION = 4          # bump when a change outside the shaders changes what a reference shows
SHADER_SUFFIXES = (".glsl", ".comp", ".vert", ".frag")
NAME = "path-traced reference"
PIXEL_FILTER = "box (a uniform random point of the pixel per path, stratified over the frames)"
STOPS = ("converged", "halves identical", "frames cap", "time cap", "fixed")
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
    max_frames: int | None = None        # render on until converged or this many frames (None: `frames` only)
    max_seconds: float | None = None     # rendering time cap of an extending reference, over all its runs

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
        if self.max_frames is not None:
            m = self.max_frames
            if isinstance(m, bool) or int(m) != m or m < self.frames or m % 2:
                raise OptionError(f"reference max_frames: must be an even integer >= frames ({self.frames}), "
                                  f"got {m!r}")
            seeds.check_length(m, "reference max_frames")
        if self.max_seconds is not None:
            t = self.max_seconds
            if isinstance(t, bool) or not (isinstance(t, (int, float)) and t >= 0 and math.isfinite(t)):
                raise OptionError(f"reference max_seconds: must be a number of seconds >= 0, got {t!r}")

    @property
    def extends(self) -> bool:
        """Whether the reference renders on until converged (max_frames above frames)."""
        return self.max_frames is not None and self.max_frames > self.frames

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
                "bounce_tolerance": self.bounce_tolerance, "bounce_check_frames": self.bounce_check_frames,
                "max_frames": self.max_frames, "max_seconds": self.max_seconds, "pixel_filter": PIXEL_FILTER}

    def cache_fields(self) -> dict:
        """What changes the rendered frames (not the caps and tolerances that decide how many)."""
        return {"frames": self.frames, "spp": self.spp, "max_bounces": self.max_bounces,
                "check_frames": self.bounce_check_frames}


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
    frames: int = 0             # frames rendered, both halves (0: settings.frames)
    rounds: list = dataclasses.field(default_factory=list)   # [offset from first_frame, frames] per render
    total_seconds: float = 0.0  # rendering seconds over every run that made or extended it (0: `seconds`)
    stop: str = "fixed"         # why it stopped rendering: one of STOPS

    def __post_init__(self):
        self.frames = self.frames or self.settings.frames
        self.rounds = [list(r) for r in self.rounds] or [[0, self.settings.frames]]
        self.total_seconds = self.total_seconds or self.seconds

    @property
    def samples_per_pixel(self) -> int:
        """Paths per pixel of the whole reference (both halves, every extension)."""
        return self.frames * self.settings.spp

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
        need = self.frames * self.noise_relmse / self.settings.tolerance
        return max(2, 2 * math.ceil(need / 2))

    @property
    def halves_identical(self) -> bool:
        """Whether A and B are equal to the bit: light without noise at these settings (one point
        light, direct light only), or a half that was never added (a GPU has given that)."""
        return bool(np.array_equal(self.half_a[..., :3], self.half_b[..., :3]))

    def stopped(self) -> str:
        """Why the reference stopped rendering, with its frames and time: one phrase."""
        s = self.settings
        done = f"{self.frames} frames x {s.spp} spp in {self.total_seconds:.0f} s"
        if self.stop == "time cap":
            return f"{done}, stopped at the {s.max_seconds:g} s time cap"
        if self.stop == "frames cap":
            return f"{done}, stopped at the {s.max_frames}-frame cap"
        if self.stop == "fixed":
            return f"{done} (a fixed count; give max_frames to render on until converged)"
        return done

    def verdict(self) -> str:
        """One line: converged or not (how many frames, and why it stopped), and whether the
        bounces suffice."""
        s = self.settings
        noise = (f"converged: halves predict relMSE {self.noise_relmse:.2e} <= tolerance {s.tolerance:.0e} "
                 f"({self.stopped()})"
                 if self.converged else
                 f"NOT converged: halves predict relMSE {self.noise_relmse:.2e} > tolerance {s.tolerance:.0e} "
                 f"({self.stopped()}; about {self.frames_to_converge()} frames of {s.spp} spp would do)")
        if self.halves_identical:
            noise = ("halves identical (noise-free light at these settings, or a half that was not rendered: the "
                     "convergence check cannot tell)")
        bounce = (f"{s.max_bounces} bounces: one more changes the mean radiance by {100 * self.bounce_change:+.2f}% "
                  f"({'within' if self.bounces_enough else 'OVER'} the {100 * s.bounce_tolerance:g}% tolerance)")
        return f"{noise}; {bounce}"

    def halves_frames(self) -> tuple[list, list]:
        """Half A's and half B's frame ranges, [start, stop) each, one per rendering round."""
        a, b = [], []
        for offset, frames in self.rounds:
            start = self.first_frame + offset
            a.append([start, start + frames // 2])
            b.append([start + frames // 2, start + frames])
        return a, b

    def as_dict(self) -> dict:
        a, b = self.halves_frames()
        return {"name": self.name, "settings": self.settings.as_dict(),
                "frames": self.frames, "samples_per_pixel": self.samples_per_pixel, "pixel_filter": PIXEL_FILTER,
                "stop": self.stop, "stopped": self.stopped(), "total_seconds": self.total_seconds,
                "seeds": {"first_frame": self.first_frame, "half_a_frames": a[0], "half_b_frames": b[0],
                          "half_a_rounds": a, "half_b_rounds": b},
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
    """The reference's render graph: `settings.spp` paths per pixel per frame, each from a random
    point of its pixel (PIXEL_FILTER), accumulated. Its wavefront runs over queues of the paths
    still going (`compact`: the same paths; most end long before the reference's many bounces)."""
    from ..graphs import path_traced

    g = path_traced(samples_per_pixel=settings.spp, max_bounces=bounces or settings.max_bounces)
    g.update_pass("PathTracer", {"pixel_jitter": True, "compact": True})
    return g


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
    """The cache key: everything that changes the reference's frames (scene content, views, size,
    ReferenceSettings.cache_fields, the path tracer's properties, the seed range, the code:
    code_digest). Not the caps: a larger one extends the cached reference."""
    tracer = reference_graph(settings).get_pass("PathTracer").get_properties()
    text = json.dumps([code_digest(), scene_digest(scene), views_digest(view_set), settings.cache_fields(),
                       first_frame, tracer], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


class ReferenceProgress:
    """Where a reference reports its rendering (the study's progress bar; by default nowhere).
    `step(frames, label)` wraps the rendering of `frames` frames and yields `tick(frames_done)`;
    `forecast(frames)` adds (or, negative, removes) frames expected to be rendered later."""

    @contextlib.contextmanager
    def step(self, frames: int, label: str):
        yield lambda done: None

    def forecast(self, frames: int) -> None:
        pass


def render_reference(scene, view_set, settings: ReferenceSettings = ReferenceSettings(), first_frame: int | None = None,
                     gpu=None, tick=None, eps: float = 1e-2) -> Reference:
    """Render the reference's first `settings.frames` frames and its checks (see the module
    docstring). `tick(frames)` is told how many frames have been rendered (of settings.frames +
    the bounce check's)."""
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


def next_extension(ref: Reference) -> tuple[int, str | None]:
    """(frames to add, None) for the reference's next extension, or (0, why it stops): converged,
    the frames cap, or a time cap the next frames would pass (at the seconds per frame so far)."""
    s = ref.settings
    if ref.halves_identical:
        return 0, "halves identical"
    if ref.converged:
        return 0, "converged"
    if not s.extends:
        return 0, "fixed"
    room = s.max_frames - ref.frames
    if room < 2:
        return 0, "frames cap"
    # at least one round, at most doubling: the forecast from few frames is itself noisy
    more = min(max(ref.frames_to_converge() - ref.frames, s.frames), ref.frames, room)
    if s.max_seconds is not None:
        per_frame = ref.total_seconds / (ref.frames + s.bounce_check_frames) if ref.total_seconds > 0 else 0.0
        affordable = (s.max_seconds - ref.total_seconds) / per_frame if per_frame > 0 else more
        more = min(more, int(affordable))
    more -= more % 2
    if more < 2:
        return 0, "time cap" if s.max_seconds is not None else "frames cap"
    return more, None


def converge(ref: Reference, render_frames, store=None, progress: ReferenceProgress | None = None) -> Reference:
    """Extend `ref` until it converges or a cap stops it (module docstring): each extension's
    frames come from `render_frames(first_frame, frames, tick) -> mean image` (its first half
    to A, its second to B); `store(ref)` after each (the cache). Returns `ref`, extended."""
    import time

    from .progressive import split_halves

    progress = progress or ReferenceProgress()
    forecast = 0
    while True:
        more, why = next_extension(ref)
        if why is not None:
            ref.stop = why
            break
        if not forecast:   # the frames the halves predict, for the ETA (consumed by the steps)
            forecast = min(ref.frames_to_converge(), ref.settings.max_frames) - ref.frames
            progress.forecast(forecast)
        half, n = more // 2, ref.frames // 2
        start = ref.first_frame + ref.frames
        t0 = time.perf_counter()
        with progress.step(more, f"reference: frames {ref.frames}..{ref.frames + more}") as tick:
            a = render_frames(start, half, tick)
            b = render_frames(start + half, half, lambda k: tick(half + k))
        took = time.perf_counter() - t0
        forecast -= more
        if forecast <= 0:
            progress.forecast(-forecast)
            forecast = 0
        mean_a = (ref.half_a.astype(np.float64) * n + a.astype(np.float64) * half) / (n + half)
        mean_b = (ref.half_b.astype(np.float64) * n + b.astype(np.float64) * half) / (n + half)
        ref.image = ((mean_a + mean_b) * 0.5).astype(np.float32)
        ref.half_a, ref.half_b = split_halves(mean_a, ref.image)
        ref.rounds.append([ref.frames, more])
        ref.frames += more
        ref.seconds += took
        ref.total_seconds += took
        if store is not None:
            store(ref)
    if forecast > 0:
        progress.forecast(-forecast)
    return ref


def cached_reference(scene, view_set, settings: ReferenceSettings = ReferenceSettings(), cache_dir=None, gpu=None,
                     tick=None, sample: int = 0, eps: float = 1e-2, render=None, render_frames=None,
                     progress: ReferenceProgress | None = None) -> Reference:
    """The reference of `scene` seen by `view_set`: from the cache when there, else rendered
    and stored (`cache_dir=False` disables the cache); then rendered on until converged or
    capped (`converge`; settings.max_frames), stored after each extension. `sample` picks the
    seed range (0 for the static view, k for trajectory sample k). `render(first_frame) ->
    Reference` renders the first round, `render_frames(first_frame, frames, tick) -> mean image`
    an extension's half (defaults: on `gpu`; rayvr.cluster splits them over workers)."""
    first = seeds.reference_first_frame(sample)
    progress = progress or ReferenceProgress()
    first_round = settings.frames + settings.bounce_check_frames

    def render_first(first_frame: int, step_tick) -> Reference:
        if render is not None:
            return render(first_frame)

        def both(n: int) -> None:
            step_tick(n)
            if tick is not None:
                tick(n)
        return render_reference(scene, view_set, settings, first_frame, gpu, both, eps)

    def rendered() -> Reference:
        with progress.step(first_round, f"frames 0..{settings.frames} and the bounce check") as step_tick:
            return render_first(first, step_tick)
    if render_frames is None:
        def render_frames(first_frame: int, frames: int, tick) -> np.ndarray:
            from .progressive import render_mean

            return render_mean(scene, reference_graph(settings), PIN, view_set, frames, first_frame, gpu=gpu,
                               tick=tick)[-1].image
    if cache_dir is False:
        return converge(rendered(), render_frames, None, progress)
    path = cache_path(scene, view_set, settings, first, cache_dir)

    def store(ref: Reference) -> None:
        store_halves(path, ref.image, ref.half_a, {
            "scene": scene.name, "views": len(view_set), "size": list(view_set.size), "first_frame": first,
            "bounce_change": ref.bounce_change, "seconds": ref.total_seconds, "frames": ref.frames,
            "rounds": ref.rounds, "settings": settings.cache_fields()})
        ref.source = str(path)

    cached = load_halves(path)
    if cached is not None:
        image, a, b, meta = cached
        ref = Reference(image, a, b, settings, first, float(meta["bounce_change"]), 0.0, str(path), eps,
                        frames=int(meta.get("frames", settings.frames)), rounds=meta.get("rounds", []),
                        total_seconds=float(meta.get("seconds", 0.0)))
    else:
        ref = rendered()
        store(ref)
    return converge(ref, render_frames, store, progress)


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
