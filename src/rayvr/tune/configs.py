"""What `rayvr.tune.measure` renders: a named configuration = graph builder + per-material effects
+ options (spp, bounces, ...), and the standard set of configurations of the error-vs-time study."""
from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable

import numpy as np

from ..errors import OptionError, did_you_mean
from ..materials.effect import Effect

# HDR pins the error is measured on, in order of preference (linear radiance, before tone mapping).
HDR_OUTPUTS = ("TAA.dst", "Composite.color", "Accumulate.dst")


def hybrid_graph(spp: int = 1, max_bounces: int = 1, path_bounces: int = 4, light_samples: int = 1, **kw):
    """`rayvr.graphs.hybrid(...)` with `spp` paths per pixel per frame for PATH_TRACED materials."""
    from ..graphs import hybrid

    g = hybrid(max_bounces=max_bounces, path_bounces=path_bounces, light_samples=light_samples, **kw)
    if "PathTracer" in g.passes:
        g.update_pass("PathTracer", {"samples_per_pixel": int(spp)})
    return g


def path_traced_graph(spp: int = 1, max_bounces: int = 4, pixel_jitter: bool = False, **kw):
    """`rayvr.graphs.path_traced(...)`: every pixel path traced from the camera. Without
    `pixel_jitter` paths start at pixel centres, as the raster G-buffer samples them."""
    from ..graphs import path_traced

    g = path_traced(samples_per_pixel=int(spp), max_bounces=max_bounces, **kw)
    g.update_pass("PathTracer", {"pixel_jitter": bool(pixel_jitter)})
    return g


@dataclasses.dataclass
class Config:
    """One configuration to measure.

    `effects`: one effect for every material, or {material name: effect} ('*' = every material
    not named). `graph(**options)` builds the render graph (default `hybrid_graph`).
    `accumulate`: frames an Accumulate pass may average (1 = the error of a single frame, as a
    moving headset sees it; 0 = no limit, a static view converging). `output`: the HDR pin whose
    error counts (default: the first of TAA.dst, Composite.color, Accumulate.dst the graph marks).
    """

    name: str
    effects: object = Effect.SHADOWS
    graph: Callable | None = None
    options: dict = dataclasses.field(default_factory=dict)
    accumulate: int = 1
    output: str | None = None

    def assignment(self, scene) -> dict[str, Effect]:
        """{material name: effect} this configuration gives `scene`'s materials."""
        names = scene.materials.names()
        if isinstance(self.effects, dict):
            spec = dict(self.effects)
            rest = Effect.parse(spec.pop("*", Effect.RASTER), where=f"config '{self.name}'.effects['*']")
            for name in spec:
                if name not in names:
                    raise OptionError(f"config '{self.name}'.effects: no material '{name}' in scene "
                                      f"'{scene.name}'{did_you_mean(name, names)}; materials: {', '.join(names)}")
            return {n: Effect.parse(spec[n], where=f"config '{self.name}'.effects['{n}']") if n in spec else rest
                    for n in names}
        effect = Effect.parse(self.effects, where=f"config '{self.name}'.effects")
        return {n: effect for n in names}

    def apply(self, scene) -> dict[str, Effect]:
        """Set the scene's material effects; returns the assignment."""
        assignment = self.assignment(scene)
        set_effects(scene, assignment)
        return assignment

    def build_graph(self):
        """The render graph, with Accumulate passes limited to `accumulate` frames."""
        builder = self.graph or hybrid_graph
        try:
            g = builder(**self.options)
        except TypeError as exc:
            raise OptionError(f"config '{self.name}': options {self.options} do not fit its graph builder "
                              f"({exc})") from None
        if int(self.accumulate) < 0:
            raise OptionError(f"config '{self.name}': accumulate must be >= 0 (0 = no limit), got {self.accumulate}")
        for name, p in g.passes.items():
            if type(p).__name__ == "Accumulate":
                g.update_pass(name, {"max_frames": int(self.accumulate)})
        return g

    def output_pin(self, graph) -> str:
        """The HDR pin whose error counts: `output`, else the first of HDR_OUTPUTS `graph` marks."""
        if self.output:
            return self.output
        for pin in HDR_OUTPUTS:
            if pin in graph.outputs:
                return pin
        raise OptionError(f"config '{self.name}': graph '{graph.name}' marks none of {', '.join(HDR_OUTPUTS)}; "
                          f"set Config.output to its linear-radiance output pin")


def set_effects(scene, assignment: dict) -> None:
    """Give the named materials their effects, touching only those that change (each change bumps
    `scene.materials.version`, which restarts accumulation and re-uploads the material buffer)."""
    for name, effect in assignment.items():
        if scene.materials[name].effect != effect:
            scene.materials[name].effect = effect


@contextlib.contextmanager
def effects_restored(scene):
    """Put the scene's material effects back as they were when the block ends."""
    saved = {m.name: m.effect for m in scene.materials}
    try:
        yield
    finally:
        set_effects(scene, saved)


def reflective_material(scene, choice: str = "auto") -> str:
    """The material that gets REFLECTIONS in the standard set: `choice`, or with 'auto' a
    material named like a floor (else a mirror), else the one with the most surface area."""
    names = scene.materials.names()
    if choice != "auto":
        if choice not in names:
            raise OptionError(f"--reflect {choice}: no material of that name{did_you_mean(choice, names)}; "
                              f"materials: {', '.join(names)}")
        return choice
    for word in ("floor", "ground", "mirror"):
        hits = [n for n in names if word in n.lower()]
        if hits:
            return hits[0]
    area = np.zeros(len(names))
    for inst in scene.instances:
        mesh = scene.meshes[inst.mesh]
        tri = mesh.triangles().astype(np.float64) @ inst.transform[:3, :3].T
        a = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        np.add.at(area, mesh.material_ids, a)
    return names[int(area.argmax())]


def standard_configs(scene, reflect: str = "auto", spp=(1, 4, 16), **options) -> list[Config]:
    """all RASTER, all SHADOWS, SHADOWS + REFLECTIONS on one material, all PATH_TRACED at each spp."""
    mirror = reflective_material(scene, reflect)
    configs = [Config("all RASTER", Effect.RASTER, options=dict(options)),
               Config("all SHADOWS", Effect.SHADOWS, options=dict(options)),
               Config(f"SHADOWS + REFLECTIONS ({mirror})", {"*": Effect.SHADOWS, mirror: Effect.REFLECTIONS},
                      options=dict(options))]
    configs += [Config(f"PATH_TRACED {n} spp", Effect.PATH_TRACED, options={**options, "spp": int(n)})
                for n in spp]
    return configs
