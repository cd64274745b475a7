"""GPU ms per pass of the hybrid's configurations side by side, on one scene and view set: the
clean preset (the default) against the raw pipeline, and each with ReSTIR DI, view reuse and
fixed foveation. What the default frame costs at a headset's size, and what each option adds.

`--effects scene` keeps the scene's own effects; `shadows` makes every material SHADOWS.
`--configs` picks rows by name (comma-separated; default all). `--quick`: the Cornell box at 2 x 32x32.
"""
from __future__ import annotations

from pathlib import Path

from rayvr.study.timing import timed_frames

from ._restir_sets import RESTIR_SETS
from ._timing import warm_up

DEFAULT_SCENE = str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb")
# row name -> rv.graphs.hybrid keywords; "raw + restir NAME" for each of _restir_sets' sets
CONFIGS = {
    "raw": {"preset": "raw"},
    "raw + restir": {"preset": "raw", "direct": "restir"},
    "clean": {},
    "clean + restir": {"direct": "restir"},
    **{f"raw + restir {name}": {"preset": "raw", "direct": "restir", "restir": props}
       for name, props in RESTIR_SETS.items() if props},
    "clean + reuse": {"reuse": "views"},
    "clean + foveation": {"foveation": "fixed"},
}


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default=DEFAULT_SCENE, help="glTF path or built-in scene name")
    parser.add_argument("--size", default="1440x1600", help="per-view WIDTHxHEIGHT")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--frames", type=int, default=40, help="timed frames per configuration")
    parser.add_argument("--effects", default="scene", choices=("scene", "shadows"))
    parser.add_argument("--configs", default=",".join(CONFIGS), help=f"rows: {', '.join(CONFIGS)}")


def run(args) -> dict:
    import rayvr as rv
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.errors import OptionError
    from rayvr.renderer import Renderer
    from rayvr.xr.cameras import default_views

    quick = args.quick
    scene = load_scene_arg("cornell_box" if quick and args.scene == DEFAULT_SCENE else args.scene)
    size = (32, 32) if quick else parse_size(args.size)
    frames, warmup = (2, 1) if quick else (args.frames, 10)
    if args.effects == "shadows":
        for m in scene.materials:
            m.effect = rv.Effect.SHADOWS
    names = [n.strip() for n in args.configs.split(",") if n.strip()]
    for n in names:
        if n not in CONFIGS:
            raise OptionError(f"--configs {n}: unknown row; use {', '.join(CONFIGS)}")
    views = default_views(scene, args.views, size)
    rows, method = [], "?"
    for name in names:
        with Renderer(scene, rv.graphs.hybrid(**CONFIGS[name]), views=views) as r:
            if not quick:
                warm_up(r)
            timing = timed_frames(r, frames, warmup)
            method = timing.method
            rays = r.profile().rays_total if hasattr(r.profile(), "rays_total") else None
        passes = {k: round(v, 3) for k, v in timing.pass_ms.items()}
        rows.append({"config": name, "views x size": f"{args.views}x{size[0]}x{size[1]}",
                     "total ms": round(sum(timing.pass_ms.values()), 3), "rays": rays, "passes": passes})
    return {"columns": ["config", "views x size", "total ms", "rays", "passes"], "rows": rows,
            "notes": [f"effects: {args.effects}; timing: {method}"]}
