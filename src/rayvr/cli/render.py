"""`rayvr render [SCENE] --views 2 --size 1440x1600 --out F`: the hybrid graph on a scene.

No SCENE renders the built-in Cornell box; a name of a built-in scene (cornell_box, spheres, ...)
renders that; anything else is a glTF file. Images per view (out_L/out_R for stereo, out_v{i} for
more views) or side by side; `.exr` writes linear HDR, `.png`/`.jpg` tone-mapped 8-bit.

Views: 1 mono, 2 stereo (--ipd apart), N a camera grid (--grid COLSxROWS, default the most
square one, e.g. 8x6 for 48; a prime N is one row) with --ipd between cameras. With --quilt the
N views are a Looking Glass light field instead: one horizontal row of cameras spanning
--view-cone, tiled into a quilt of --grid (default as above) tiles, written to exactly the
--quilt path (--quilt-suffix appends Looking Glass's `_qs{cols}x{rows}a{aspect}`).

Every output path is checked for writability before rendering; all files of one render are
written under temporary names and renamed together at the end, so a failure or Ctrl-C leaves
none of them.
`--camera-path FILE` (a path `rayvr view` recorded) renders one frame per recorded pose into
out_0000, out_0001, ...
`--denoise svgf` filters the light with SVGF and TAA (shadows, reflections and path-traced pixels
then converge over --frames); `--denoise oidn` runs Intel Open Image Denoise on the last frame
(the `oidn` extra: pip install 'rayvr[oidn]'). `--direct restir` samples the direct light of
SHADOWS materials and above by ReSTIR (rayvr.passes.ReSTIRDI) instead of the light table alone.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import OptionError, did_you_mean
from ..fileio import atomic_group, check_writable, image_format, write_exr, write_image
from ..graph_options import DEFAULT_PRESET, NONE, OPTIONS, PRESETS
from ..graphs import BUILDERS, COMMAND_LINE_GRAPHS
from ..passes.gbuffer.lighting_pass import MAX_LIGHT_SAMPLES
from ..passes.probe_gi.layout import MAX_PROBES_PER_AXIS
from ..passes.rt_reflections.rt_reflections import MAX_REFLECTION_BOUNCES
from . import cluster as cluster_cli
from .options import (MAX_VIEWS, add_lighting_arguments, add_pass_property_argument, add_trace_arguments,
                      apply_lighting, apply_pass_properties, integer, load_scene_arg,
                      number, parse_size, say_nonfinite, trace_options, views_count)

LAYOUTS = ("per-view", "side-by-side")
PT_SPP_PER_FRAME = 8   # the most paths per pixel one path-traced frame traces
OUT_SUFFIXES = (".png", ".jpg", ".jpeg", ".exr")
MAX_IPD_M = 1.0   # metres: eyes are 0.05-0.08 apart; a light-field grid's spacing stays below a metre


def register(sub) -> None:
    """Add the `render` subcommand to the CLI's subparsers."""
    p = sub.add_parser("render", help="render a scene (the hybrid graph, or path traced) and write images")
    p.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: the Cornell box)")
    p.add_argument("--views", type=views_count(), default=2,
                   help=f"view count: 1 mono, 2 stereo, N a camera grid (1 to {MAX_VIEWS}; default 2)")
    p.add_argument("--size", default="256x256", help="per-view size WIDTHxHEIGHT (default 256x256)")
    p.add_argument("--out", default="out/render.png",
                   help="output image: .png or .jpg (tone mapped) or .exr (HDR); default out/render.png")
    p.add_argument("--layout", default="per-view", choices=LAYOUTS, help="one file per view, or side by side")
    p.add_argument("--effect", action="append", default=[], metavar="MATERIAL=EFFECT",
                   help="set a material's effect (raster, shadows, reflections, path_traced); '*' for all; repeatable")
    p.add_argument("--tonemap", default="aces", help="aces, reinhard or linear (default aces)")
    p.add_argument("--exposure", default="auto",
                   help="exposure in stops (-64 to 64), or 'auto' for the frame's mean luminance (default auto)")
    p.add_argument("--max-bounces", type=integer("--max-bounces", 1, MAX_REFLECTION_BOUNCES), default=1,
                   help=f"reflection bounces, 1 to {MAX_REFLECTION_BOUNCES} (default 1)")
    p.add_argument("--light-samples", type=integer("--light-samples", 1, MAX_LIGHT_SAMPLES), default=1,
                   help=f"light samples per pixel, 1 to {MAX_LIGHT_SAMPLES} (default 1)")
    p.add_argument("--frames", type=integer("--frames", 1, 100_000), default=1,
                   help="frames to render, 1 to 100000 (timings average over them)")
    p.add_argument("--ipd", type=number("--ipd", 0, MAX_IPD_M, low_open=True, unit=" metres"), default=0.063,
                   help="eye distance for stereo, or camera spacing of a grid, in metres: > 0 and <= 1 "
                        "(default 0.063)")
    p.add_argument("--grid", help="COLSxROWS: the camera grid of N views, or with --quilt the quilt's tiles; "
                                  "its product must equal --views (default: the most square grid)")
    p.add_argument("--quilt", metavar="FILE", help="also write a Looking Glass quilt (.png or .jpg) of the views, "
                                                   "which then lie on one horizontal line of cameras")
    p.add_argument("--quilt-suffix", action="store_true",
                   help="append Looking Glass's _qs{cols}x{rows}a{aspect} to the --quilt file name")
    p.add_argument("--view-cone", type=number("--view-cone", 0, 180, low_open=True, high_open=True, unit=" degrees"),
                   default=40.0, help="the quilt's view cone in degrees, > 0 and < 180 (default 40)")
    p.add_argument("--multiview", default="auto", choices=("auto", "on", "off"), help="G-buffer multiview")
    p.add_argument("--gbuffer", default="auto", choices=("auto", "raster", "rt"),
                   help="G-buffer: raster, ray-traced, or auto (ray-traced on GPUs with weak raster units)")
    p.add_argument("--graph", default="hybrid", choices=COMMAND_LINE_GRAPHS,
                   help=" or ".join(f"{name} ({BUILDERS[name].help})" for name in COMMAND_LINE_GRAPHS))
    p.add_argument("--spp", type=integer("--spp", 1, 1 << 20),
                   help="path_traced: samples per pixel accumulated in all (default: --frames x 1); hybrid: "
                        "paths per frame for PATH_TRACED materials (default 1)")
    p.add_argument("--bounces", type=integer("--bounces", 1, 1024),
                   help="path tracing bounces B: the longest path has B scattering vertices, each sampling a "
                        "light, so B = 1 is direct light only; Mitsuba 3's max_depth is B + 1, Tauray's "
                        "'2 bounces + NEE' is B = 3 (default: 8 path_traced, 4 hybrid)")
    add_lighting_arguments(p)
    p.add_argument("--preset", default=DEFAULT_PRESET, choices=tuple(PRESETS),
                   help="hybrid: clean (default: probe GI, SVGF and TAA, a denoised frame that converges while "
                        "the view is still) or raw (the bare pipeline: one frame's light, nothing across frames); "
                        "--gi, --denoise and --taa override it")
    for option in OPTIONS:
        preset_decides = option.name in PRESETS[DEFAULT_PRESET]
        p.add_argument(f"--{option.name}", choices=option.cli_choices,
                       help=option.cli_help("the preset's for hybrid, none for path_traced" if preset_decides else NONE))
    p.add_argument("--taa", choices=("on", "off"),
                   help="hybrid: TAA after the composite (jittered frames averaged, exactly while the view is "
                        "still); default the preset's")
    p.add_argument("--probes", metavar="XxYxZ", help="with --gi probes: probes per axis over the scene's bounds "
                                                     "(default 8x8x8)")
    p.add_argument("--probe-rays", type=integer("--probe-rays", 16, 1024), help="with --gi probes: rays per probe "
                                                                                "per frame, 16 to 1024 (default 128)")
    add_trace_arguments(p)
    add_pass_property_argument(p)
    p.add_argument("--report", action="store_true", help="print the graph's compile report (the profile, with the "
                                                         "rays traced per view, is printed either way)")
    cluster_cli.add_arguments(p)
    p.add_argument("--camera-path", metavar="FILE",
                   help="replay a camera path JSON (rayvr view records them): one frame per pose, "
                        "written as OUT_0000, OUT_0001, ...")
    p.set_defaults(func=run)


def resolve_graph_options(args) -> None:
    """Fill --gi, --denoise and --taa left out: the preset's for hybrid, off for path_traced (a
    given --gi there is refused later, with the reason)."""
    preset = PRESETS[args.preset] if args.graph == "hybrid" else {}
    for key in (o.name for o in OPTIONS):
        if getattr(args, key) is None:
            setattr(args, key, preset.get(key) or NONE)
    if args.taa is None:
        args.taa = "on" if preset.get("taa") else "off"


def probe_options(args) -> dict | None:
    """ProbeGI properties from --probes and --probe-rays (None without --gi probes)."""
    if args.gi != "probes":
        for flag, value in (("--probes", args.probes), ("--probe-rays", args.probe_rays)):
            if value is not None:
                raise OptionError(f"{flag} sets up irradiance probes; add --gi probes (or leave {flag} out)")
        return None
    out = {}
    if args.probes is not None:
        m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*[xX]\s*(\d+)\s*", str(args.probes))
        counts = [int(g) for g in m.groups()] if m else []
        if not counts or min(counts) < 1 or max(counts) > MAX_PROBES_PER_AXIS:
            raise OptionError(f"--probes {args.probes}: expected XxYxZ probes per axis, each 1 to "
                              f"{MAX_PROBES_PER_AXIS}, e.g. --probes 8x8x8")
        out["counts"] = counts
    if args.probe_rays is not None:
        out["rays_per_probe"] = args.probe_rays
    return out


def parse_exposure(text) -> tuple[bool, float]:
    """(auto, stops): 'auto' or a finite number of stops in [-64, 64]."""
    if str(text).strip().lower() == "auto":
        return True, 0.0
    try:
        return False, number("--exposure", -64, 64, unit=" stops")(text)
    except OptionError:
        raise OptionError(f"--exposure {text}: give stops from -64 to 64 (e.g. 0, 1.5, -1) or 'auto'") from None


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


def choose_grid(args) -> tuple[int, int] | None:
    """The camera grid (or the quilt's tiles): --grid, checked against --views, else the most
    square grid of --views (None for mono and stereo without a quilt)."""
    from ..xr.cameras import grid_for_views
    from ..xr.quilt import parse_grid

    if args.grid:
        grid = parse_grid(args.grid)
        if grid[0] * grid[1] != args.views:
            cols, rows = grid_for_views(args.views)
            raise OptionError(f"--grid {args.grid} has {grid[0] * grid[1]} views but --views is {args.views}; "
                              f"give a grid of {args.views} (e.g. --grid {cols}x{rows}) or --views "
                              f"{grid[0] * grid[1]}")
        return grid
    if args.views <= 2 and not args.quilt:
        return None
    return grid_for_views(args.views)


def quilt_path(args, grid, size) -> Path | None:
    """Exactly the --quilt path, or with --quilt-suffix the Looking Glass name; its format is
    checked now (PNG or JPEG by the suffix)."""
    from ..xr.quilt import quilt_filename

    if not args.quilt:
        if args.quilt_suffix:
            raise OptionError("--quilt-suffix names a quilt file: give --quilt FILE with it")
        return None
    if args.views < 2:
        raise OptionError(f"--quilt needs a light field of 2 or more views; --views is {args.views}")
    image_format(args.quilt, "--quilt")
    path = Path(args.quilt)
    return quilt_filename(path, grid[0], grid[1], size[0] / size[1]) if args.quilt_suffix else path


def run(args) -> int:
    """`rayvr render`: validate the options and outputs, render with the hybrid graph (here, or
    over the workers of a cluster with --workers), write every image at once."""
    from ..passes.tonemap import OPERATORS
    from ..xr.cameras import default_views

    resolve_graph_options(args)
    size = parse_size(args.size, views=args.views)
    if args.tonemap.lower() not in OPERATORS:
        raise OptionError(f"--tonemap {args.tonemap}: use one of {', '.join(OPERATORS)}")
    auto_exposure, exposure = parse_exposure(args.exposure)
    out = Path(args.out)
    if out.suffix.lower() not in OUT_SUFFIXES:
        raise OptionError(f"--out {args.out}: write .png or .jpg (tone mapped) or .exr (HDR)")
    if args.graph == "path_traced" and args.gi != NONE:
        raise OptionError("--gi probes: lights the hybrid graph's materials; --graph path_traced traces its own "
                          "indirect light (leave --gi out)")
    if args.direct != NONE and args.graph == "path_traced":
        raise OptionError(f"--direct {args.direct}: samples the hybrid graph's direct light; --graph path_traced "
                          f"samples its own (leave --direct out)")
    probes = probe_options(args)
    grid = choose_grid(args)
    quilt = quilt_path(args, grid, size)
    paths = output_paths(out, args.views, args.layout)
    if quilt is not None and quilt.resolve() in {p.resolve() for p in paths}:
        raise OptionError(f"--quilt {quilt}: is also a view's output file; give the quilt its own name")
    for path in paths:
        check_writable(path, "--out")
    if quilt is not None:
        check_writable(quilt, "--quilt")
    camera_path = None
    if args.camera_path:
        from ..xr.camera_path import CameraPath

        if args.views > 2 or args.grid or quilt is not None:
            raise OptionError(f"--camera-path replays 1 or 2 views, not --views {args.views}; use --views 1 or 2")
        if args.frames != 1:
            raise OptionError("--camera-path renders one frame per recorded pose; leave out --frames")
        if cluster_cli.requested(args):
            raise OptionError("--camera-path renders in this process; leave out --workers")
        camera_path = CameraPath.load(args.camera_path)
    if args.graph == "path_traced" and args.spp is not None and args.frames != 1:
        raise OptionError(f"--spp {args.spp} and --frames {args.frames}: path_traced accumulates --spp samples "
                          f"over as many frames as it needs; give one of them")
    for option in OPTIONS:   # what a choice needs (pyoidn for --denoise oidn), before the scene loads
        value = getattr(args, option.name)
        if value != NONE:
            option[value].require(f"--{option.name} {value}")
    graph = build_graph(args, exposure, auto_exposure, probes, grid)   # a bad option or --set is refused
    apply_pass_properties(graph, args.pass_properties)                  # before the scene loads and warns
    scene = load_scene_arg(args.scene)
    apply_effects(scene, args.effect)
    apply_lighting(scene, args)

    if quilt is not None:
        from ..xr.quilt import quilt_views

        views = quilt_views(scene, grid[0], grid[1], size, args.view_cone)
    else:
        views = default_views(scene, args.views, size, ipd=args.ipd, grid=grid)
    hdr = out.suffix.lower() == ".exr"
    if camera_path is not None:
        with atomic_group():   # every frame's files, or none
            written = render_path(args, scene, graph, views, hdr, camera_path, out)
        for path in written:
            print(f"wrote {path}")
        return 0
    quilt_grid = grid if quilt is not None else None
    if cluster_cli.requested(args):
        pixels, quilt_pixels = cluster_cli.render(args, args.scene, scene, graph, views, hdr, quilt_grid)
    else:
        pixels, quilt_pixels = render_here(args, scene, graph, views, hdr, quilt_grid)
    images = [np.concatenate(list(pixels), axis=1)] if args.layout == "side-by-side" else list(pixels)
    with atomic_group():
        for path, img in zip(paths, images):
            write_exr(path, img) if hdr else write_image(path, img)
        if quilt is not None:
            write_image(quilt, quilt_pixels, alpha=True)
    for path in paths:
        print(f"wrote {path}")
    if quilt is not None:
        print(f"wrote {quilt} (quilt of {grid[0]}x{grid[1]} tiles, view aspect {size[0] / size[1]:.4g}, "
              f"views on one horizontal line)")
    return 0


def path_traced_frames(args) -> tuple[int, int]:
    """(frames, samples per pixel per frame) of a path_traced render: --spp in all (exactly), or
    --frames of one sample each."""
    if args.spp is None:
        return args.frames, 1
    per_frame = max(d for d in range(1, PT_SPP_PER_FRAME + 1) if args.spp % d == 0)
    return args.spp // per_frame, per_frame


def build_graph(args, exposure: float, auto_exposure: bool, probes: dict | None = None, grid=None):
    """The graph --graph names, with the path tracing, denoising, trace decision and (hybrid)
    probe options."""
    from ..graphs import hybrid, path_traced

    # the reuse's grid: a quilt's cameras are one row whatever its tiles
    trace = trace_options(args, args.views if args.quilt else (grid[0] if grid else 0))
    if args.graph == "path_traced":
        _, per_frame = path_traced_frames(args)
        return path_traced(samples_per_pixel=per_frame, max_bounces=args.bounces or 8, tonemap=args.tonemap.lower(),
                           exposure=exposure, auto_exposure=auto_exposure, denoise=args.denoise, **trace)
    g = hybrid(max_bounces=args.max_bounces, tonemap=args.tonemap.lower(), exposure=exposure,
               auto_exposure=auto_exposure, light_samples=args.light_samples, multiview=args.multiview,
               gbuffer=args.gbuffer, path_bounces=args.bounces or 4, denoise=args.denoise,
               gi=None if args.gi == NONE else args.gi, taa=args.taa == "on", probes=probes,
               direct=None if args.direct == NONE else args.direct, **trace)
    if args.spp is not None:
        g.update_pass("PathTracer", {"samples_per_pixel": args.spp})
    return g


def summarize(r, args, line: str) -> None:
    """After a render: the compile report (--report), `line`, the profile, and on stderr the
    passes that set non-finite samples to 0."""
    nonfinite = r.compiled.nonfinite_counts()   # exact, and the report's and profile's from here on
    r.compiled.ray_counts()   # exact: the profile's rays per view are the last frame's
    if args.report:
        print(r.report())
    print(line)
    print(r.profile())
    say_nonfinite(nonfinite)


def render_here(args, scene, graph, views, hdr: bool, quilt_grid=None) -> tuple:
    """Render in this process: (pixels (views, h, w, c) rows top-down, the quilt's pixels when
    `quilt_grid` (cols, rows) is given, else None)."""
    from tqdm import tqdm

    from ..graphs import OUTPUT, hdr_output
    from ..renderer import Renderer

    size = views.size
    quilt_pixels = None
    frames = path_traced_frames(args)[0] if args.graph == "path_traced" else args.frames
    with Renderer(scene, graph, views=views) as r:
        oidn = r.compiled.passes.get("Denoise")
        for i in tqdm(range(frames), desc=f"render {scene.name}", unit="frame", leave=False,
                      disable=frames < 8):
            if oidn is not None:   # OIDN is offline work: only the frame that is written
                oidn.set_properties({"enabled": i == frames - 1})
            r.render()
        pixels = r.read_output(hdr_output(graph) if hdr else OUTPUT, flip_y=True)
        spp = f", {frames * graph.get_pass('PathTracer').samples_per_pixel} spp" if args.graph == "path_traced" else ""
        summarize(r, args, f"{scene.name}: {len(views)} view(s) of {size[0]}x{size[1]}, {frames} frame(s){spp}")
        if quilt_grid is not None:
            from ..xr.quilt import compose_quilt, read_quilt

            quilt_pixels = read_quilt(compose_quilt(r.gl, r.output_texture(OUTPUT), *quilt_grid))
    return pixels, quilt_pixels


def render_path(args, scene, graph, views, hdr: bool, camera_path, out: Path) -> list[Path]:
    """Replay `camera_path`: one frame per pose, its views written as out_0000..., (inside the
    caller's atomic group: the files appear together at its end)."""
    from ..graphs import OUTPUT, hdr_output
    from ..renderer import Renderer

    written = []
    with Renderer(scene, graph, views=views) as r:
        for i in range(len(camera_path)):
            r.render(camera_path.view_set(i, views))
            pixels = r.read_output(hdr_output(graph) if hdr else OUTPUT, flip_y=True)
            images = [np.concatenate(list(pixels), axis=1)] if args.layout == "side-by-side" else list(pixels)
            for path, img in zip(output_paths(frame_path(out, i), len(views), args.layout), images):
                written.append(write_exr(path, img) if hdr else write_image(path, img))
        summarize(r, args, f"{scene.name}: {len(views)} view(s) of {views.size[0]}x{views.size[1]}, "
                           f"{len(camera_path)} frame(s)")
    return written
