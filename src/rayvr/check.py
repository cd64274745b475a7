"""Scene health check: render a scene with every ready-made graph and effect level and count the
non-finite values (NaN, +-Inf) each pass writes into each of its output textures.

    findings = run_check(scene, size=(32, 32), views=2, frames=2)
    bad = [f for f in findings if f.nonfinite]

Counts come from `nonfinite_by_pass(compiled, ...)`, which wraps the compiled graph's step list
for the probed frames (this tool only): after each pass it asks the pass for GPU counters
(`render_pass.nonfinite_counts() -> {pin: count}`, when a pass has them) and otherwise reads back
every float texture the pass wrote. Transient textures alias, so they are read right after their
writer runs, before a later pass reuses the memory. A mask (views, h, w) of the texels holding a
non-finite component comes with every pin that has any. Each pass that scrubs non-finite
samples (COUNTS_NONFINITE) also gets a finding for its GPU counter, pin SCRUBBED: a NaN or Inf
that it set to 0 is a fault upstream even though its output is finite.
"""
from __future__ import annotations

import contextlib
import dataclasses

import numpy as np

from .errors import RayvrError
from .materials.effect import Effect

FLOAT_DTYPES = ("f2", "f4")
# The pseudo-pin of a pass's GPU counter of non-finite samples it set to 0 (over all the frames;
# glsl/nonfinite.glsl): the values it would otherwise have written are gone, so no mask.
SCRUBBED = "scrubbed samples"


@dataclasses.dataclass
class PinFinding:
    """One output texture of one pass in one configuration: how many values were not finite."""

    config: str                 # 'hybrid RASTER', 'path_traced', ...
    pass_name: str
    pin: str
    values: int                 # components checked per frame (texels x channels x views)
    nonfinite: int              # of them NaN or +-Inf, in the worst frame
    mask: np.ndarray | None = None   # (views, h, w) bool, rows top-down, where any frame had one
    source: str = "readback"    # or "gpu counters"


@dataclasses.dataclass
class ConfigFailure:
    """A configuration that could not compile or render (a RayvrError, e.g. a shader error)."""

    config: str
    error: str


def _written_textures(compiled, pass_name: str) -> list[tuple[str, object, np.dtype]]:
    """(pin, texture, numpy dtype) of every float texture `pass_name` writes."""
    from .rendergraph.formats import NUMPY_DTYPES, get_format
    from .rendergraph.render_pass import PinKind

    out = []
    for ref, res in compiled.plan.resources.items():
        writer, pin = ref.split(".", 1)
        if writer != pass_name or res.kind is not PinKind.TEXTURE:
            continue
        fmt = get_format(res.fmt)
        if fmt.dtype in FLOAT_DTYPES:
            out.append((pin, compiled.resources[ref], np.dtype(NUMPY_DTYPES[fmt.dtype])))
    return out


def _read_mask(texture, dtype) -> tuple[int, int, np.ndarray]:
    """(values, non-finite values, (layers, h, w) mask top-down) of a texture array."""
    raw = np.frombuffer(texture.read(), dtype).reshape(texture.layers, texture.height, texture.width, -1)
    bad = ~np.isfinite(raw)
    return raw.size, int(bad.sum()), bad.any(axis=-1)[:, ::-1]


@contextlib.contextmanager
def nonfinite_by_pass(compiled, config: str, findings: dict):
    """While inside, every `compiled.execute()` adds per-pass, per-pin counts to `findings`
    ({(pass, pin): PinFinding}). Restores the compiled graph's steps on exit."""
    original = compiled._steps

    def probe(name, run):
        render_pass = compiled.passes[name]
        textures = _written_textures(compiled, name)

        def step(ctx, data):
            run(ctx, data)
            ctx.gl.memory_barrier()   # the graph orders passes only for passes: this readback too
            counters = getattr(render_pass, "nonfinite_counts", None)
            gpu_counts = counters() if callable(counters) else None
            for pin, tex, dtype in textures:
                values = tex.width * tex.height * tex.layers * tex.components
                if gpu_counts is not None and pin in gpu_counts and not gpu_counts[pin]:
                    count, mask, source = 0, None, "gpu counters"
                else:
                    values, count, mask = _read_mask(tex, dtype)
                    source = "readback"
                f = findings.setdefault((name, pin), PinFinding(config, name, pin, values, 0, source=source))
                f.nonfinite = max(f.nonfinite, count)
                if count:
                    f.mask = mask if f.mask is None else (f.mask | mask)
        return step

    compiled._steps = [(probe(name, run), data, bits) for name, (run, data, bits) in zip(compiled.order, original)]
    try:
        yield findings
    finally:
        compiled._steps = original


def configurations() -> list[tuple[str, object, Effect | None]]:
    """(name, graph factory, effect for every material or None) of every ready-made graph at
    every effect level (the path tracer ignores effects: once)."""
    import functools

    from . import graphs

    out = []
    raw = functools.partial(graphs.hybrid, preset="raw")
    svgf = functools.partial(graphs.hybrid, preset="raw", denoise="svgf")
    taa = functools.partial(graphs.hybrid_taa, preset="raw")
    for name, factory in (("hybrid", raw), ("hybrid_taa", taa), ("hybrid svgf", svgf)):
        out += [(f"{name} {e.name}", factory, e) for e in Effect]
    # probe GI reaches DirectLighting at RASTER and every lighting pass at REFLECTIONS
    out += [(f"hybrid clean {e.name}", _probe_gi_graph, e) for e in (Effect.RASTER, Effect.REFLECTIONS)]
    out.append(("path_traced", graphs.path_traced, None))
    out.append(("path_traced svgf", functools.partial(graphs.path_traced, denoise="svgf"), None))
    return out


def _probe_gi_graph():
    """The clean hybrid (probe GI, SVGF, TAA) with a small probe grid (check looks for NaN and Inf,
    not quality)."""
    from . import graphs

    return graphs.hybrid(gi="probes", probes={"counts": [4, 4, 4], "rays_per_probe": 32, "warmup": 2})


def run_check(scene, size=(32, 32), views: int = 2, frames: int = 2, gpu=None, progress: bool = False):
    """Render `scene` in every configuration for `frames` frames with every pass probed.
    Returns (findings: [PinFinding], failures: [ConfigFailure]). Materials are put back as they
    were. `progress`: a tqdm bar over the configurations."""
    from tqdm import tqdm

    from .renderer import Renderer
    from .xr.cameras import default_views

    view_set = default_views(scene, views, size)
    saved = [m.effect for m in scene.materials]
    findings: list[PinFinding] = []
    failures: list[ConfigFailure] = []
    try:
        for name, factory, effect in tqdm(configurations(), desc="check", unit="config", disable=not progress,
                                          leave=False):
            if effect is not None:
                for m in scene.materials:
                    m.effect = effect
            found: dict = {}
            try:
                with Renderer(scene, factory(), views=view_set, gpu=gpu, profiling=False) as r:
                    with nonfinite_by_pass(r.compiled, name, found):
                        for _ in range(frames):
                            r.render()
                    for pass_name, count in r.compiled.nonfinite_counts().items():
                        found[(pass_name, SCRUBBED)] = PinFinding(name, pass_name, SCRUBBED, 0, count,
                                                                  source="gpu counters")
            except RayvrError as exc:
                failures.append(ConfigFailure(name, " ".join(str(exc).split())))
            findings += found.values()
    finally:
        for m, e in zip(scene.materials, saved):
            m.effect = e
    return findings, failures
