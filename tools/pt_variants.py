#!/usr/bin/env python3
"""GPU time of graph variants and of source trees side by side (a device-machine tool).

    python3 tools/pt_variants.py OUT.jsonl [RUN ...] [--measures cornell,tauray,spheres] [--rounds 2]
    python3 tools/pt_variants.py --list                  # the variants and what each sets

A variant is a named property set, {pass name: {property: value}}, applied to every graph a
measure builds (graph.update_pass, so an unknown property is refused with the pass's own message);
a pass the graph lacks is skipped, and a variant none of whose passes any measured graph has is an
error row. Its key "scene" sets attributes of every scene a measure loads instead (`bvh_layout`). A RUN is `VARIANT` (in this checkout) or `TREE:VARIANT`, where TREE is a `--tree
NAME=DIR` or a folder `.ab/NAME` (a git worktree of another commit: tools/ab_trees.py makes one);
`old` and `prev` alone mean `old:base` and `prev:base`. `--define NAME='{"Shadows": {"view_group": 8}}'`
adds a variant without an edit here.

Each RUN is a child process with the tree's src/ first on PYTHONPATH. Measures (`--measures`):
- cornell, tauray, spheres: the path tracer on pt_peer's scenes and cameras (.scenes/: the Cornell
  box, tauray/test.glb with one sun, MetalRoughSpheresNoTextures with one sun; --size 1920x1080,
  --spp 1 (a list: a row part per count), --bounces 3, Russian roulette off): the PathTracer pass's
  GPU ms (timer queries: fastest and mean of --frames frames after a 1 s warm-up) and the image's
  mean radiance;
- hybrid: the hybrid graph on tauray at 2x1440x1600, every material SHADOWS, then REFLECTIONS;
- views: 64 views of 512x683 against one view of their pixels (tauray, the hybrid graph);
- gi: benchmarks probe_gi's frame (tauray, SHADOWS with REFLECTIONS on one material, 2x1440x1600)
  with and without probe GI, GPU ms per pass;
- gi_views: 64 views against one with probe GI, per pass, and their ratio;
- rays: the tree's own `benchmarks rays` (primary and diffuse Grays/s) on tauray and the spheres.
RUNs go in the order given, --rounds times (A B A B ...), so clock drift shows as a difference
between rounds. `--div N` divides every size by N (a smoke test on llvmpipe). On the GPU machine run
it after the preamble that ../shared/tools/gpu-prep prints, or through `tools/gpu-bench variants`.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"cornell": ("cornell/cornell_box.gltf", "cornell.json"), "tauray": ("tauray_test.glb", "tauray.json"),
          "spheres": ("MetalRoughSpheresNoTextures.glb", "spheres.json")}
PT_MEASURES = tuple(SCENES)
MEASURES = (*PT_MEASURES, "hybrid", "views", "gi", "gi_views", "rays")


def _tiles88() -> dict:
    """Each ray pass's workgroups as 8x8 tiles: GBufferRT over one view, RTShadows over 8 views
    (the shapes before each pass was given a one-warp workgroup)."""
    return {"GBuffer": {"tile": [8, 8]}, "Shadows": {"tile": [8, 8], "view_group": 8}}


SCENE = "scene"   # a variant's scene attributes, not a pass

# name -> {pass name: properties}. Pass names are the ready-made graphs' (rayvr.graphs): GBuffer,
# Shadows, Reflections, Composite, PathTracer, Probes.
VARIANTS: dict[str, dict] = {
    "base": {},
    "pcg": {"PathTracer": {"sampler": "pcg"}},
    "wavefront": {"PathTracer": {"kernel": "wavefront"}},
    "megakernel": {"PathTracer": {"kernel": "megakernel"}},
    # probe GI's hybrid tracing reflections on every REFLECTIONS pixel, however rough (the cutoff's saving)
    "trace_rough_reflections": {"GBuffer": {"reflection_max_roughness": 1.0}},
    # RTReflections over the compaction's pixel list instead of the whole image in tiles
    "reflections_list": {"Reflections": {"dispatch_mode": "list"}},
    "shadows_list": {"Shadows": {"dispatch_mode": "list"}},
    # the reflected hits' probe lookups in the traversal kernel (no records, one dispatch)
    "reflections_lookup_in_kernel": {"Reflections": {"defer_probes": False}},
    "gb_raster": {"GBuffer": {"mode": "raster"}},
    "gb_rt": {"GBuffer": {"mode": "rt"}},
    # the views a workgroup spans and the tiles (PT measures: gi_views, gi): GBufferRT 4x8 over 2 views,
    # RTShadows 8x4 over 16 and HybridComposite with probes 8x4 over 4 by default
    **{f"gb_vg{n}": {"GBuffer": {"view_group": n}} for n in (1, 4, 8)},
    "gb_tile88": {"GBuffer": _tiles88()["GBuffer"]},
    **{f"sh_vg{n}": {"Shadows": {"view_group": n}} for n in (1, 2, 4, 8)},
    "sh_tile88": {"Shadows": _tiles88()["Shadows"]},
    "tiles88": _tiles88(),
    **{f"co_vg{n}": {"Composite": {"probe_view_group": n}} for n in (1, 2, 8)},
    "co_tile88": {"Composite": {"probe_tile": [8, 8], "probe_view_group": 1}},
    "tiles88_all": {**_tiles88(), "Composite": {"probe_tile": [8, 8], "probe_view_group": 1}},
    # the traced BVH: compressed 8-wide nodes (rayvr.scene.bvh8) instead of the BVH4
    "bvh8": {SCENE: {"bvh_layout": "bvh8"}},
    # the wavefront path tracer's knobs: per-bounce queues of the paths still going, the trace kernel's
    # persistent threads over them, one-warp workgroups (8x4 of one view), the queues sorted by direction
    "compact": {"PathTracer": {"compact": True}},
    "persistent": {"PathTracer": {"persistent": True}},
    "pt_tile84": {"PathTracer": {"tile": [8, 4], "view_group": 1}},
    "bvh8_compact": {SCENE: {"bvh_layout": "bvh8"}, "PathTracer": {"compact": True}},
    "bvh8_persistent": {SCENE: {"bvh_layout": "bvh8"}, "PathTracer": {"persistent": True}},
    # each bounce's queue sorted by the octant of its BSDF rays
    "sort_dirs": {"PathTracer": {"sort_directions": True}},
    "bvh8_sort": {SCENE: {"bvh_layout": "bvh8"}, "PathTracer": {"sort_directions": True}},
    # RTShadows' shadow rays through alphaMode BLEND: Russian roulette below a transmittance of 0.25,
    # or a coin per surface (1.0), against the exact product
    "blend_rr25": {"Shadows": {"blend_roulette": 0.25}},
    "blend_coin": {"Shadows": {"blend_roulette": 1.0}},
}


def apply_scene(scene, props: dict) -> None:
    """Set the variant's scene attributes (its SCENE part) on `scene`; an unknown one is refused."""
    for key, value in props.get(SCENE, {}).items():
        if not hasattr(scene, key):
            raise SystemExit(f"variant: the scene has no attribute {key!r}")
        setattr(scene, key, value)


def apply_variant(graph, props: dict) -> set[str]:
    """Set `props` ({pass name: properties}) on the passes of `graph` that it names; the names of
    the passes it set. A pass refuses an unknown property or a bad value (OptionError)."""
    applied = set()
    for name, values in props.items():
        if name != SCENE and name in graph.passes:
            graph.update_pass(name, values)
            applied.add(name)
    return applied


def raw_hybrid(**kw):
    """The tree's bare hybrid graph: `preset="raw"`, or in trees from before presets the default."""
    import inspect

    import rayvr as rv

    raw = {"preset": "raw"} if "preset" in inspect.signature(rv.graphs.hybrid).parameters else {}
    return rv.graphs.hybrid(**raw, **kw)


class Child:
    """One RUN's measures in its tree (the child process): every graph goes through `graph()`."""

    def __init__(self, config: dict):
        self.props = config["props"]
        self.opt = config["options"]
        self.tree_root = config["tree_root"]
        self.applied: set[str] = set()

    def graph(self, g):
        self.applied |= apply_variant(g, self.props)
        return g

    def div(self, w: int, h: int) -> tuple[int, int]:
        d = int(self.opt["div"])
        return w // d, h // d

    def scene(self, file: str):
        import rayvr as rv

        scene = rv.load_scene(str(ROOT / ".scenes" / file))
        apply_scene(scene, self.props)
        if self.opt["opaque"]:   # trees from before stochastic transparency drew BLEND as OPAQUE
            from rayvr.scene.model import AlphaMode
            for m in scene.materials:
                m.alpha_mode = AlphaMode.OPAQUE
        return scene

    def warm_and_time(self, r) -> None:
        """Render for 1 s, then --frames frames into a fresh profile."""
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < 1.0:
            r.render()
        r.gl.finish()
        if hasattr(r.compiled, "reset_profile"):
            r.compiled.reset_profile()
        for _ in range(int(self.opt["frames"])):
            r.render()
        r.gl.finish()

    def passes_ms(self, r) -> dict:
        passes = r.profile().passes
        return {"total": round(float(sum(p.mean_ms for p in passes.values())), 4),
                **{k: round(float(p.mean_ms), 4) for k, p in passes.items()}}

    def path_tracer(self, key: str) -> dict:
        import numpy as np

        import rayvr as rv
        from rayvr.scene.model import Light, LightType
        from rayvr.xr.cameras import look_at, mono_view
        from rayvr.xr.views import Fov

        file, cam_file = SCENES[key]
        cam = json.loads((ROOT / ".scenes" / cam_file).read_text())
        W, H = self.div(*(int(x) for x in self.opt["size"].split("x")))
        scene = self.scene(file)
        if "sun" in cam:
            scene.lights = [Light(type=LightType.DIRECTIONAL, direction=cam["sun"], intensity=cam.get("sun_lux", 8.0))]
        pose = look_at(np.array(cam["eye"], float), np.array(cam["target"], float))
        view = mono_view(pose, Fov.symmetric(cam["yfov_deg"], W / H), (W, H), near=cam.get("near", 0.01), far=1e4)
        out = {}
        for spp in (int(n) for n in str(self.opt["spp"]).split(",")):
            g = self.graph(rv.graphs.path_traced(samples_per_pixel=spp, max_bounces=int(self.opt["bounces"]),
                                                 rr_start=100))
            with rv.Renderer(scene, g, views=view) as r:
                self.warm_and_time(r)
                pt = r.profile().passes["PathTracer"]
                img = np.asarray(r.read_output("Accumulate.dst"))[..., :3]
                out[f"spp{spp}"] = {"gpu_min_ms": round(float(pt.min_ms), 4), "gpu_mean_ms": round(float(pt.mean_ms), 4),
                                    "mean_radiance": round(float(img.mean()), 5),
                                    "nonfinite": int((~np.isfinite(img)).sum())}
        return out[next(iter(out))] if len(out) == 1 else out

    def frame(self, scene, graph, views, size=None):
        import rayvr as rv

        kw = {"size": size} if size is not None else {}
        with rv.Renderer(scene, self.graph(graph), views=views, **kw) as r:
            self.warm_and_time(r)
            out = self.passes_ms(r)
        return out if self.opt["passes"] else out["total"]

    def hybrid(self) -> dict:
        import rayvr as rv

        scene, out = self.scene("tauray_test.glb"), {}
        for effect in ("SHADOWS", "REFLECTIONS"):
            for m in scene.materials:
                m.effect = getattr(rv.Effect, effect)
            out[f"all_{effect.lower()}_ms"] = self.frame(scene, raw_hybrid(), 2, self.div(1440, 1600))
        return out

    def views(self) -> dict:
        scene = self.scene("tauray_test.glb")
        many = self.frame(scene, raw_hybrid(), 64, self.div(512, 683))
        one = self.frame(scene, raw_hybrid(), 1, tuple(8 * s for s in self.div(512, 683)))
        if isinstance(many, dict):
            return {"views64": many, "one_view": one, "ratio": round(many["total"] / one["total"], 4)}
        return {"views64_ms": many, "one_view_ms": one, "ratio": round(many / one, 4)}

    def _import_benchmarks(self) -> None:
        """Put the tree's benchmarks/ on sys.path, or this checkout's for a `--src` tree (src/ alone)."""
        own = (Path(self.tree_root) / "benchmarks").is_dir()
        sys.path.insert(0, str(self.tree_root if own else ROOT))

    def _probe_gi(self):
        """The tree's benchmarks probe_gi graph and material setup, and its default_views."""
        self._import_benchmarks()
        from benchmarks.probe_gi import _effects, _graph
        try:
            from rayvr.xr.cameras import default_views
        except ImportError:
            from rayvr.renderer import default_views
        return _effects, _graph, default_views

    def gi(self) -> dict:
        import rayvr as rv

        effects, graph, default_views = self._probe_gi()
        scene = self.scene("tauray_test.glb")
        effects(scene)
        if self.opt["gi_all_reflections"]:   # rough materials go to the probes with GI
            for m in scene.materials:
                m.effect = rv.Effect.REFLECTIONS
        out = {}
        for gi in (False, True):
            probes = {"counts": self.opt["gi_probes"]} if self.opt["gi_probes"] and gi else {}
            views = default_views(scene, 2, self.div(1440, 1600))
            with rv.Renderer(scene, self.graph(graph(gi, **probes)), views=views) as r:
                self.warm_and_time(r)
                out["gi" if gi else "no_gi"] = self.passes_ms(r)
        return out

    def gi_views(self) -> dict:
        import rayvr as rv

        effects, graph, default_views = self._probe_gi()
        scene = self.scene("tauray_test.glb")
        effects(scene)
        w, h = self.div(512, 683)
        out = {}
        for key, view_set in (("views64", default_views(scene, 64, (w, h), grid=(8, 8))),
                              ("one_view", default_views(scene, 1, (8 * w, 8 * h)))):
            with rv.Renderer(scene, self.graph(graph(True)), views=view_set) as r:
                self.warm_and_time(r)
                out[key] = self.passes_ms(r)
        out["ratio"] = round(out["views64"]["total"] / out["one_view"]["total"], 4)
        return out

    def rays(self) -> dict:
        """The tree's own `benchmarks rays` at 1920x1080 (its default BVH layout; a `--src` tree
        has none, so this checkout's); no graph, so no variant applies."""
        self._import_benchmarks()
        from benchmarks import rays

        parser = argparse.ArgumentParser()
        rays.add_arguments(parser)
        files = {"tauray": "tauray_test.glb", "spheres": "MetalRoughSpheresNoTextures.glb"}
        w, h = self.div(1920, 1080)
        args = parser.parse_args(["--scenes", ",".join(str(ROOT / ".scenes" / f) for f in files.values()),
                                  "--size", f"{w}x{h}", "--rounds", "2"])
        args.quick = False
        out = {}
        for name, row in zip(files, rays.run(args)["rows"]):
            out[f"{name}_primary_Grays_s"] = round(float(row["primary_Grays_s"]), 4)
            out[f"{name}_diffuse_Grays_s"] = round(float(row["diffuse_Grays_s"]), 4)
        return out

    def measure(self, key: str) -> dict:
        return self.path_tracer(key) if key in PT_MEASURES else getattr(self, key)()


def child_main(config: dict) -> None:
    child, out = Child(config), {}
    for key in config["measures"]:
        try:
            out[key] = child.measure(key)
        except Exception as e:   # noqa: BLE001 (a broken run is a row, not the end of the run)
            out[key] = {"error": f"{type(e).__name__}: {str(e)[:300]}"}
    graphs_built = any(k != "rays" for k in config["measures"])
    missing = sorted(set(child.props) - child.applied - {SCENE})
    if missing and graphs_built:
        out["error"] = f"no measured graph has the variant's pass(es) {', '.join(missing)}"
    print("RESULT " + json.dumps(out), flush=True)


def resolve_run(run: str, trees: dict, variants: dict) -> tuple[str, Path, dict]:
    """(label, tree root, properties) of a RUN: VARIANT or TREE:VARIANT."""
    tree, _, name = run.rpartition(":")
    if not tree and name not in variants and (name in trees or (ROOT / ".ab" / name).is_dir()):
        tree, name = name, "base"   # `old`, `prev`: that tree as it is
    if name not in variants:
        raise SystemExit(f"unknown variant {name!r}; known: {', '.join(variants)} (or --define NAME=JSON)")
    if tree:
        root = trees.get(tree, ROOT / ".ab" / tree)
        if not (Path(root) / "src" / "rayvr").is_dir():
            raise SystemExit(f"tree {tree!r}: {root} has no src/rayvr (make it with "
                             f"`python3 tools/ab_trees.py COMMIT {tree}`, or pass --tree {tree}=DIR)")
        return run, Path(root).resolve(), variants[name]
    return run, ROOT, variants[name]


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", nargs="?", type=Path, help="JSON lines file the rows are appended to")
    p.add_argument("runs", nargs="*", help="VARIANT or TREE:VARIANT (default: every variant here)")
    p.add_argument("--measures", default="cornell,tauray,spheres", help=f"comma-separated: {', '.join(MEASURES)}")
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--tree", action="append", default=[], metavar="NAME=DIR", help="a source tree (a checkout root)")
    p.add_argument("--define", action="append", default=[], metavar="NAME=JSON",
                   help='one more variant: {"Pass": {"property": value}}')
    p.add_argument("--size", default="1920x1080", help="the path tracer measures' image")
    p.add_argument("--spp", default="1", help="the path tracer measures' samples per pixel, e.g. 1,4,8")
    p.add_argument("--bounces", type=int, default=3, help="the path tracer measures' max_bounces")
    p.add_argument("--frames", type=int, default=40, help="timed frames after the warm-up")
    p.add_argument("--div", type=int, default=1, help="every size divided by this (a smoke test on llvmpipe)")
    p.add_argument("--passes", action="store_true", help="hybrid, views: each pass's mean GPU ms, not only the sum")
    p.add_argument("--opaque", action="store_true", help="every material OPAQUE (for trees without stochastic "
                                                          "transparency)")
    p.add_argument("--gi-probes", help="gi: the probe volume, e.g. 16,16,16 (default: the pass's)")
    p.add_argument("--gi-all-reflections", action="store_true", help="gi: every material REFLECTIONS")
    p.add_argument("--timeout", type=int, default=240, help="seconds per child")
    p.add_argument("--list", action="store_true", help="print the variants and exit")
    return p.parse_intermixed_args(argv)


def main(argv=None) -> int:
    if argv is None and len(sys.argv) >= 3 and sys.argv[1] == "--child":
        child_main(json.loads(sys.argv[2]))
        return 0
    args = parse_args(argv)
    variants = dict(VARIANTS)
    for d in args.define:
        name, _, text = d.partition("=")
        variants[name] = json.loads(text)
    if args.list:
        for name, props in variants.items():
            print(f"{name:28} {json.dumps(props)}")
        return 0
    if args.out is None:
        raise SystemExit("name the output file (OUT.jsonl)")
    measures = args.measures.split(",")
    unknown = sorted(set(measures) - set(MEASURES))
    if unknown:
        raise SystemExit(f"unknown measure(s) {', '.join(unknown)}; known: {', '.join(MEASURES)}")
    trees = dict(t.split("=", 1) for t in args.tree)
    runs = [resolve_run(r, trees, variants) for r in (args.runs or list(variants))]
    options = {"size": args.size, "spp": args.spp, "bounces": args.bounces, "frames": args.frames, "div": args.div,
               "passes": args.passes,
               "opaque": args.opaque, "gi_all_reflections": args.gi_all_reflections,
               "gi_probes": [int(n) for n in args.gi_probes.split(",")] if args.gi_probes else None}
    commit = os.environ.get("RAYVR_COMMIT", "unknown")
    for rnd in range(1, args.rounds + 1):
        for label, root, props in runs:
            config = {"measures": measures, "props": props, "options": options, "tree_root": str(root)}
            env = dict(os.environ, PYTHONPATH=f"{root / 'src'}:{os.environ.get('PYTHONPATH', '')}")
            t = time.perf_counter()
            try:   # a child past --timeout is killed, and its row says so: the next runs still go
                p = subprocess.run([sys.executable, __file__, "--child", json.dumps(config)], env=env,
                                   capture_output=True, text=True, timeout=args.timeout, check=False)
                lines = [line for line in p.stdout.splitlines() if line.startswith("RESULT ")]
                res = json.loads(lines[-1][7:]) if lines else {"error": p.stderr[-800:]}
            except subprocess.TimeoutExpired:
                res = {"error": f"timed out after {args.timeout} s (--timeout)"}
            row = {"variant": label, "round": rnd, "commit": commit, "wall_s": round(time.perf_counter() - t, 1), **res}
            print(json.dumps(row), flush=True)
            with args.out.open("a") as f:
                f.write(json.dumps(row) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
