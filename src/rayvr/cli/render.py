"""`rayvr render [SCENE] --views 2 --size 1440x1600 --out F`: the hybrid graph on a scene.

No SCENE renders the built-in Cornell box; a name of a built-in scene (cornell_box, spheres, ...)
renders that; anything else is a glTF file. PNGs per view (out_L/out_R for stereo, out_v{i} for
more views) or side by side; `.exr` writes linear HDR. `--camera-path FILE` (a path `rayvr view`
recorded) renders one frame per recorded pose into out_0000, out_0001, ... Files are written under
a temporary name in the same folder and renamed, so a failure never leaves a half-written output.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import OptionError, did_you_mean
from ..fileio import write_exr, write_png
from .options import load_scene_arg, parse_size

LAYOUTS = ("per-view", "side-by-side")


def register(sub) -> None:
    """Add the `render` subcommand to the CLI's subparsers."""
    p = sub.add_parser("render", help="render a scene with the hybrid graph and write images")
    p.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: the Cornell box)")
    p.add_argument("--views", type=int, default=2, help="view count: 1 mono, 2 stereo, N a camera grid (default 2)")
    p.add_argument("--size", default="256x256", help="per-view size WIDTHxHEIGHT (default 256x256)")
    p.add_argument("--out", default="out/render.png", help="output image: .png (tone mapped) or .exr (HDR)")
    p.add_argument("--layout", default="per-view", choices=LAYOUTS, help="one file per view, or side by side")
    p.add_argument("--effect", action="append", default=[], metavar="MATERIAL=EFFECT",
                   help="set a material's effect (raster, shadows, reflections, path_traced); '*' for all; repeatable")
    p.add_argument("--tonemap", default="aces", help="aces, reinhard or linear (default aces)")
    p.add_argument("--exposure", default="auto",
                   help="exposure in stops, or 'auto' for the frame's mean luminance (default auto)")
    p.add_argument("--max-bounces", type=int, default=1, help="reflection bounces (default 1)")
    p.add_argument("--light-samples", type=int, default=1, help="light samples per pixel (default 1)")
    p.add_argument("--frames", type=int, default=1, help="frames to render (timings average over them)")
    p.add_argument("--ipd", type=float, default=0.063, help="eye distance in metres for stereo (default 0.063)")
    p.add_argument("--grid", help="light-field camera grid COLSxROWS (its product must equal --views)")
    p.add_argument("--quilt", help="also write a Looking Glass quilt PNG of the views (with --grid)")
    p.add_argument("--multiview", default="auto", choices=("auto", "on", "off"), help="G-buffer multiview")
    p.add_argument("--gbuffer", default="auto", choices=("auto", "raster", "rt"),
                   help="G-buffer: raster, ray-traced, or auto (ray-traced on GPUs with weak raster units)")
    p.add_argument("--report", action="store_true", help="print the graph's compile report")
    p.add_argument("--camera-path", metavar="FILE",
                   help="replay a camera path JSON (rayvr view records them): one frame per pose, "
                        "written as OUT_0000, OUT_0001, ...")
    p.set_defaults(func=run)


def parse_exposure(text) -> tuple[bool, float]:
    """(auto, stops): 'auto' or a number of stops."""
    if str(text).strip().lower() == "auto":
        return True, 0.0
    try:
        return False, float(text)
    except ValueError:
        raise OptionError(f"--exposure {text}: give stops (e.g. 0, 1.5, -1) or 'auto'") from None


def apply_effects(scene, specs) -> None:
    """Apply '--effect MATERIAL=EFFECT' options; '*' sets every material."""
    from ..materials.effect import Effect

    names = [m.name for m in scene.materials]
    for spec in specs:
        if "=" not in spec:
            raise OptionError(f"--effect {spec}: expected MATERIAL=EFFECT, e.g. --effect Floor=reflections")
        name, value = (s.strip() for s in spec.split("=", 1))
        effect = Effect.parse(value, where=f"--effect {spec}")
        if name == "*":
            for m in scene.materials:
                m.effect = effect
            continue
        if name not in names:
            raise OptionError(f"--effect {spec}: no material '{name}' in the scene{did_you_mean(name, names)}; "
                              f"materials: {', '.join(names)}")
        scene.materials[name].effect = effect


def output_paths(out: Path, views: int, layout: str) -> list[Path]:
    """Where each view goes: out itself (mono or side by side), out_L/out_R, or out_v{i}."""
    if views == 1 or layout == "side-by-side":
        return [out]
    if views == 2:
        return [out.with_name(f"{out.stem}_L{out.suffix}"), out.with_name(f"{out.stem}_R{out.suffix}")]
    return [out.with_name(f"{out.stem}_v{i}{out.suffix}") for i in range(views)]


def frame_path(out: Path, index: int) -> Path:
    """Frame `index` of a camera path replay: out_0000.png, out_0001.png, ..."""
    return out.with_name(f"{out.stem}_{index:04d}{out.suffix}")


def write_views(out: Path, pixels: np.ndarray, layout: str) -> list[Path]:
    """Write (views, h, w, c) rows top-down: one file per view or side by side; .exr as HDR."""
    hdr = out.suffix.lower() == ".exr"
    images = [np.concatenate(list(pixels), axis=1)] if layout == "side-by-side" else list(pixels)
    return [(write_exr if hdr else write_png)(path, img)
            for path, img in zip(output_paths(out, len(pixels), layout), images)]


def run(args) -> int:
    """`rayvr render`: validate the options, render with the hybrid graph, write the images."""
    from ..graphs import HDR_OUTPUT, OUTPUT, hybrid
    from ..passes.tonemap import OPERATORS
    from ..renderer import Renderer, default_views

    size = parse_size(args.size)
    if args.views < 1:
        raise OptionError(f"--views {args.views}: need at least 1 view")
    if args.frames < 1:
        raise OptionError(f"--frames {args.frames}: need at least 1 frame")
    if args.tonemap.lower() not in OPERATORS:
        raise OptionError(f"--tonemap {args.tonemap}: use one of {', '.join(OPERATORS)}")
    auto_exposure, exposure = parse_exposure(args.exposure)
    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".exr"):
        raise OptionError(f"--out {args.out}: write .png (tone mapped) or .exr (HDR)")
    grid = None
    if args.grid:
        from ..xr.quilt import parse_grid

        grid = parse_grid(args.grid)
    if args.quilt and grid is None:
        raise OptionError("--quilt needs --grid COLSxROWS (e.g. --views 48 --grid 8x6 --quilt q.png)")
    camera_path = None
    if args.camera_path:
        from ..xr.camera_path import CameraPath

        if args.views > 2 or grid is not None:
            raise OptionError(f"--camera-path replays 1 or 2 views, not --views {args.views}; use --views 1 or 2")
        if args.frames != 1:
            raise OptionError("--camera-path renders one frame per recorded pose; leave out --frames")
        camera_path = CameraPath.load(args.camera_path)
    scene = load_scene_arg(args.scene)
    apply_effects(scene, args.effect)

    views = default_views(scene, args.views, size, ipd=args.ipd, grid=grid)
    graph = hybrid(max_bounces=args.max_bounces, tonemap=args.tonemap.lower(), exposure=exposure,
                   auto_exposure=auto_exposure, light_samples=args.light_samples,
                   multiview=args.multiview, gbuffer=args.gbuffer)
    hdr = out.suffix.lower() == ".exr"
    written = []
    with Renderer(scene, graph, views=views) as r:
        if camera_path is None:
            for _ in range(args.frames):
                r.render()
            pixels = r.read_output(HDR_OUTPUT if hdr else OUTPUT, flip_y=True)
        else:
            for i in range(len(camera_path)):
                r.render(camera_path.view_set(i, views))
                written += write_views(frame_path(out, i), r.read_output(HDR_OUTPUT if hdr else OUTPUT,
                                                                         flip_y=True), args.layout)
        if args.report:
            print(r.report())
        frames = args.frames if camera_path is None else len(camera_path)
        print(f"{scene.name}: {len(views)} view(s) of {size[0]}x{size[1]}, {frames} frame(s)")
        print(r.profile())
        if args.quilt:
            from ..xr.quilt import compose_quilt, quilt_filename, write_quilt_png

            q = compose_quilt(r.gl, r.output_texture(OUTPUT), *grid)
            qpath = quilt_filename(args.quilt, grid[0], grid[1], size[0] / size[1])
            written.append(write_quilt_png(q, qpath))
    if camera_path is None:
        written += write_views(out, pixels, args.layout)
    for path in written:
        print(f"wrote {path}")
    return 0
