"""What the error study renders: a named configuration = graph + per-material effects + settings
(spp, bounces, light samples, frames accumulated, denoiser, GI, direct light sampling), and the
standard set of them.

A configuration states its settings in full (`Config.settings(scene)`): the graph builder's
defaults with the configuration's options over them, so every row of a report says what it ran.
The PATH_TRACED levels default to the reference's bounces, so that they converge to it.

A denoiser, probe GI or ReSTIR is one more option of the graph builder (`denoise=`, `gi=`,
`direct=`); the standard set includes a row for each value rayvr.graph_options lists for an option
the builder takes (rayvr.graphs.BUILDERS), those whose extra is installed.

Configurations from a file (`load_configs`): JSON, a list or {"configs": [...]} of
    {"name": "mirror floor", "effects": {"*": "shadows", "Floor": "reflections"},
     "graph": "hybrid" | "hybrid_taa" | "path_traced", "options": {"spp": 4}, "accumulate": 1}
"""
from __future__ import annotations

import contextlib
import dataclasses
import inspect
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..fileio import read_json
from ..errors import OptionError, did_you_mean
from ..graph_options import DENOISE, DIRECT, GI
from ..graphs import BUILDERS, HDR_OUTPUTS
from ..materials.effect import Effect
from .reference import ReferenceSettings

DEFAULT_BOUNCES = ReferenceSettings.max_bounces


# The study's configurations name every option they turn on: the graphs start from the raw preset.
STUDY_PRESET = "raw"


def hybrid_graph(spp: int = 1, max_bounces: int = 1, path_bounces: int = DEFAULT_BOUNCES, light_samples: int = 1,
                 preset: str = STUDY_PRESET, **kw):
    """`rv.graphs.hybrid(...)` with `spp` paths per pixel per frame for PATH_TRACED materials
    (`path_bounces` bounces; `max_bounces` is the reflections'), from the raw preset unless
    `preset` names another."""
    from ..graphs import hybrid

    g = hybrid(max_bounces=max_bounces, path_bounces=path_bounces, light_samples=light_samples, preset=preset, **kw)
    if "PathTracer" in g.passes:
        g.update_pass("PathTracer", {"samples_per_pixel": int(spp)})
    return g


def hybrid_taa_graph(spp: int = 1, max_bounces: int = 1, path_bounces: int = DEFAULT_BOUNCES,
                     light_samples: int = 1, preset: str = STUDY_PRESET, **kw):
    """`rv.graphs.hybrid_taa(...)` (TAA before tone mapping) with `spp` and the preset as in
    `hybrid_graph`."""
    from ..graphs import hybrid_taa

    g = hybrid_taa(max_bounces=max_bounces, path_bounces=path_bounces, light_samples=light_samples, preset=preset,
                   **kw)
    if "PathTracer" in g.passes:
        g.update_pass("PathTracer", {"samples_per_pixel": int(spp)})
    return g


def path_traced_graph(spp: int = 1, max_bounces: int = DEFAULT_BOUNCES, pixel_jitter: bool = False, **kw):
    """`rv.graphs.path_traced(...)`: every pixel path traced from the camera. Without
    `pixel_jitter` paths start at pixel centres, as the raster G-buffer samples them."""
    from ..graphs import path_traced

    g = path_traced(samples_per_pixel=int(spp), max_bounces=max_bounces, **kw)
    g.update_pass("PathTracer", {"pixel_jitter": bool(pixel_jitter)})
    return g


GRAPHS = {"hybrid": hybrid_graph, "hybrid_taa": hybrid_taa_graph, "path_traced": path_traced_graph}


def builder_defaults(builder) -> dict:
    """Every keyword the builder takes and its default: its own, over those of the ready-made
    graph it wraps (rayvr.graphs.BUILDERS, by its name in GRAPHS)."""
    name = next((k for k, v in GRAPHS.items() if v is builder), None)
    own = {key: p.default for key, p in inspect.signature(builder).parameters.items()
           if p.default is not inspect.Parameter.empty}
    return {**(BUILDERS[name].defaults(own.get("preset")) if name else {}), **own}


def accepts(builder, option: str) -> bool:
    """Whether `builder` (or the rv.graphs function it wraps) takes keyword `option`."""
    return option in builder_defaults(builder)


@dataclasses.dataclass
class Config:
    """One configuration to measure.

    `effects`: one effect for every material, or {material name: effect} ('*' = every material
    not named). `graph`: a name of GRAPHS or a builder `graph(**options)` (default "hybrid").
    `accumulate`: frames an Accumulate pass averages before the image is judged (1 = each frame
    alone, what a moving head sees). `output`: the HDR pin whose error counts (default: the
    first of TAA.dst, Composite.color, Accumulate.dst the graph marks).
    """

    name: str
    effects: object = Effect.SHADOWS
    graph: str | Callable | None = None
    options: dict = dataclasses.field(default_factory=dict)
    accumulate: int = 1
    output: str | None = None

    def __post_init__(self):
        if not isinstance(self.accumulate, int) or isinstance(self.accumulate, bool) or self.accumulate < 1:
            raise OptionError(f"config '{self.name}': accumulate must be an integer >= 1 (frames averaged "
                              f"before the image is judged), got {self.accumulate!r}")
        if isinstance(self.graph, str) and self.graph not in GRAPHS:
            raise OptionError(f"config '{self.name}': graph {self.graph!r} is unknown"
                              f"{did_you_mean(self.graph, GRAPHS)}; use one of {', '.join(GRAPHS)}")

    @property
    def builder(self) -> Callable:
        if self.graph is None:
            return hybrid_graph
        return GRAPHS[self.graph] if isinstance(self.graph, str) else self.graph

    @property
    def graph_name(self) -> str:
        if isinstance(self.graph, str):
            return self.graph
        return next((k for k, v in GRAPHS.items() if v is self.builder), getattr(self.builder, "__name__", "graph"))

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
        """The render graph; its Accumulate passes average `accumulate` frames (1: each frame
        passes through)."""
        try:
            g = self.builder(**self.options)
        except TypeError as exc:
            raise OptionError(f"config '{self.name}': options {self.options} do not fit its graph builder "
                              f"({exc})") from None
        for name, p in g.passes.items():
            if type(p).__name__ == "Accumulate":
                g.update_pass(name, {"enabled": self.accumulate > 1, "max_frames": int(self.accumulate)})
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

    def settings(self, scene=None) -> dict:
        """Everything this configuration renders with, stated: graph, spp, bounces, reflection
        bounces, light samples, frames accumulated, denoiser, GI, direct light sampling (and the
        effects on `scene`)."""
        merged = {**builder_defaults(self.builder), **self.options}
        path_traced = self.builder is path_traced_graph
        out = {"graph": self.graph_name,
               "spp": int(merged.get("spp", merged.get("samples_per_pixel", 1))),
               "bounces": int(merged.get("max_bounces" if path_traced else "path_bounces", 0)),
               "reflection_bounces": None if path_traced else merged.get("max_bounces"),
               "light_samples": None if path_traced else merged.get("light_samples"),
               "frames_accumulated": int(self.accumulate),
               "denoiser": merged.get("denoise") or "none",
               "gi": merged.get("gi") or "none",
               "direct": merged.get("direct") or "none",
               "options": dict(self.options)}
        if scene is not None:
            out["effects"] = {k: v.name for k, v in self.assignment(scene).items()}
        return out

    def key(self, scene) -> str:
        """What the configuration's converged image depends on (the bias floor's cache key)."""
        return json.dumps([self.graph_name, sorted(self.options.items()),
                           sorted((k, v.name) for k, v in self.assignment(scene).items()), self.output],
                          default=str)


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


def available_denoisers(builder=hybrid_graph) -> list[str]:
    """The denoisers (rayvr.graph_options.DENOISE) whose extra is installed, if `builder` takes
    `denoise=`."""
    return list(DENOISE.available_values()) if accepts(builder, "denoise") else []


def available_gi(builder=hybrid_graph) -> list[str]:
    """The GI modes (rayvr.graph_options.GI) whose extra is installed, if `builder` takes `gi=`."""
    return list(GI.available_values()) if accepts(builder, "gi") else []


def available_direct(builder=hybrid_graph) -> list[str]:
    """The direct-light samplers (rayvr.graph_options.DIRECT), if `builder` takes `direct=`."""
    return list(DIRECT.available_values()) if accepts(builder, "direct") else []


def standard_configs(scene, reference: ReferenceSettings | None = None, reflect: str = "auto", spp=(1, 4, 16),
                     taa: bool = True, denoised_levels: bool = True, probes: dict | None = None,
                     foveation: str | None = None, **options) -> list[Config]:
    """Every effect level alone (all RASTER, all SHADOWS, all REFLECTIONS, all PATH_TRACED at each
    `spp`) and mixed (SHADOWS with REFLECTIONS on one material); PATH_TRACED 1 spp + TAA (judged in
    motion); each PATH_TRACED level with every available denoiser, each other level with probe GI
    where the graphs have it, with each direct-light sampler where it has ray-traced shadows
    (`all SHADOWS + restir direct`) and (`denoised_levels`) with the real-time denoiser, with and
    without probe GI. PATH_TRACED uses the reference's bounces. `probes`: the probe GI rows' ProbeGI
    properties (e.g. {"counts": [4, 4, 4]}; default the pass's). `foveation` ('fixed' or 'gaze'):
    also each level with rays (SHADOWS and above, and the mixed one) foveated, judged beside its
    unfoveated row by FLIP in the fovea and weighted by eccentricity too (rayvr.study.metrics)."""
    bounces = (reference or ReferenceSettings()).max_bounces
    opts = {"path_bounces": bounces, **options}
    mirror = reflective_material(scene, reflect)
    levels = [("all RASTER", Effect.RASTER), ("all SHADOWS", Effect.SHADOWS), ("all REFLECTIONS", Effect.REFLECTIONS),
              (f"SHADOWS + REFLECTIONS ({mirror})", {"*": Effect.SHADOWS, mirror: Effect.REFLECTIONS})]
    configs = [Config(name, effects, options=dict(opts)) for name, effects in levels]
    if foveation not in (None, "none"):
        configs += [Config(f"{name} + {foveation} foveation", effects, options={**opts, "foveation": foveation})
                    for name, effects in levels[1:]]
    for mode in available_gi():
        configs += [Config(f"{name} + {mode} GI", effects, options={**opts, **_gi(mode, probes)})
                    for name, effects in levels]
    for mode in available_direct():
        configs += [Config(f"{name} + {mode} direct", effects, options={**opts, "direct": mode})
                    for name, effects in levels if effects != Effect.RASTER]
    traced = [(f"PATH_TRACED {n} spp", {**opts, "spp": int(n)}) for n in spp]
    configs += [Config(name, Effect.PATH_TRACED, options=o) for name, o in traced]
    if taa:
        configs.append(Config(f"PATH_TRACED {min(spp)} spp + TAA", Effect.PATH_TRACED, graph="hybrid_taa",
                              options={**opts, "spp": int(min(spp))}))
    for d in available_denoisers():
        configs += [Config(f"{name} + {d.upper()}", Effect.PATH_TRACED, options={**o, "denoise": d})
                    for name, o in traced]
    if denoised_levels:   # the hybrid's one-sample light through SVGF (OIDN is offline: no frame budget)
        for d in (d for d in available_denoisers() if DENOISE[d].realtime):
            for gi in [None, *available_gi()]:
                extra = {"denoise": d, **(_gi(gi, probes) if gi else {})}
                configs += [Config(f"{name}{f' + {gi} GI' if gi else ''} + {d.upper()}", effects,
                                   options={**opts, **extra}) for name, effects in levels]
    return configs


def _gi(mode: str, probes: dict | None) -> dict:
    """The graph options of GI `mode` with the probe properties `probes`."""
    return {"gi": mode, **({"probes": dict(probes)} if probes else {})}


CONFIG_FIELDS = ("name", "effects", "graph", "options", "accumulate", "output")


def load_configs(path) -> list[Config]:
    """Configurations from a JSON file (see the module docstring); errors name the file and entry."""
    path = Path(path)
    doc = read_json(path, f"--configs {path}")
    items = doc.get("configs") if isinstance(doc, dict) else doc
    if not isinstance(items, list) or not items:
        raise OptionError(f"--configs {path}: expected a non-empty list of configurations (top level or "
                          f"under \"configs\")")
    configs = []
    for i, item in enumerate(items):
        where = f"--configs {path}: configs[{i}]"
        if not isinstance(item, dict) or not isinstance(item.get("name"), str) or not item["name"]:
            raise OptionError(f"{where}: expected an object with at least a \"name\" string")
        unknown = sorted(set(item) - set(CONFIG_FIELDS))
        if unknown:
            raise OptionError(f"{where}: unknown field '{unknown[0]}'{did_you_mean(unknown[0], CONFIG_FIELDS)}; "
                              f"fields: {', '.join(CONFIG_FIELDS)}")
        if not isinstance(item.get("options", {}), dict):
            raise OptionError(f"{where}.options: expected an object such as {{\"spp\": 4}}")
        try:
            configs.append(Config(item["name"], item.get("effects", "shadows"), item.get("graph", "hybrid"),
                                  dict(item.get("options", {})), item.get("accumulate", 1), item.get("output")))
        except OptionError as exc:
            raise OptionError(f"{where}: {exc}") from None
    return configs
