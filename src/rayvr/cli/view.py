"""`rayvr view [SCENE] [--graph hybrid|path_traced|FILE] [--views 1|2] [--size WxH]`: a live window.

`--frames N --screenshot out.png` draws N frames, writes the window with its UI and exits (for
scripts and tests); `--script events.json` plays timed key and mouse events (rayvr.viewer.script).
Without a display or without the viewer extra it exits 2 with one line saying what is missing.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import OptionError
from .options import add_trace_arguments, parse_size, trace_options


def register(sub) -> None:
    """Add the `view` subcommand to the CLI's subparsers."""
    p = sub.add_parser("view", help="open a live window on a scene (needs a display and rayvr[viewer])")
    p.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: the Cornell box)")
    p.add_argument("--graph", default="hybrid",
                   help="hybrid (default), path_traced, or a saved graph (.json, or a .py script: it runs)")
    p.add_argument("--views", type=int, default=2, choices=(1, 2), help="1 mono or 2 stereo (default 2)")
    p.add_argument("--size", default="512x512", help="per-view render size WIDTHxHEIGHT (default 512x512)")
    p.add_argument("--window", help="window size WIDTHxHEIGHT (default: the views side by side)")
    p.add_argument("--preset", help="headset preset for per-eye fov, IPD and size (index, quest2, quest3, vive_pro2)")
    p.add_argument("--preset-scale", type=float, default=1.0,
                   help="render the preset's panel size times this (default 1; e.g. 0.25 on a software renderer)")
    p.add_argument("--effect", action="append", default=[], metavar="MATERIAL=EFFECT",
                   help="set a material's effect (raster, shadows, reflections, path_traced); '*' for all; repeatable")
    p.add_argument("--assignment", metavar="FILE",
                   help="effects from a JSON {material: effect} or a rayvr tune report's tune.json")
    p.add_argument("--frames", type=int, help="draw this many frames, then exit")
    p.add_argument("--screenshot", metavar="FILE", help="after the last frame write the window (.png) "
                                                      "or the HDR output (.exr); needs --frames")
    p.add_argument("--script", metavar="FILE", help="timed input events (JSON, see rayvr.viewer.script)")
    p.add_argument("--record", metavar="FILE", help="record the camera path (a pose per frame) to FILE at exit, "
                                                  "for rayvr render --camera-path")
    p.add_argument("--target-frames", type=int, default=0, metavar="N",
                   help="stop rendering once N frames have accumulated since the view or scene last changed "
                        "(the frame stays on screen; 0: never)")
    p.add_argument("--target-seconds", type=float, default=0.0, metavar="S",
                   help="... or once S seconds have passed since then (0: never)")
    p.add_argument("--no-ui", action="store_true", help="start with the panels hidden (H toggles them)")
    add_trace_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    """`rayvr view`: check the options, the extra and the display, then run the window."""
    from ..viewer.deps import require_display, require_extra

    size = parse_size(args.size)
    window = parse_size(args.window, "--window") if args.window else None
    if args.frames is not None and args.frames < 1:
        raise OptionError(f"--frames {args.frames}: draw at least 1 frame")
    if args.screenshot:
        if args.frames is None:
            raise OptionError("--screenshot needs --frames N (the frame to write); a --script can take "
                              "screenshots at any frame")
        if Path(args.screenshot).suffix.lower() not in (".png", ".exr"):
            raise OptionError(f"--screenshot {args.screenshot}: write .png (the window) or .exr (HDR output)")
    if args.target_frames < 0 or args.target_seconds < 0:
        raise OptionError("--target-frames and --target-seconds: give 0 (no target) or more")
    if args.record and Path(args.record).suffix.lower() != ".json":
        raise OptionError(f"--record {args.record}: a camera path is a .json file")
    if args.preset:
        from ..xr.presets import get_preset

        get_preset(args.preset)
        if not 0 < args.preset_scale <= 1:
            raise OptionError(f"--preset-scale {args.preset_scale}: use a factor in (0, 1]")
    trace = trace_options(args)
    if (trace["reuse"] or trace["foveation"]) and not builder_name_of(args.graph):
        raise OptionError(f"--reuse/--foveation build the ready-made graph with a trace decision; --graph "
                          f"{args.graph} is a saved graph: add a TraceDecision to it instead")
    require_extra()
    script = None
    if args.script:   # checked before a window opens
        import glfw

        from ..viewer.script import InputScript
        from ..viewer.window import key_names

        script = InputScript.load(args.script, key_names(glfw).values())
    require_display()

    from ..viewer.app import Viewer, builder_name, resolve_graph, resolve_scene
    from ..viewer.assignment import apply_assignment, load_assignment
    from .render import apply_effects

    scene = resolve_scene(args.scene)
    graph = args.graph if builder_name(args.graph) else resolve_graph(args.graph)   # by name: its options in the panel
    apply_effects(scene, args.effect)
    if args.assignment:
        apply_assignment(scene, load_assignment(args.assignment, scene))
    viewer = Viewer(scene, graph, views=args.views, size=size, preset=args.preset, preset_scale=args.preset_scale,
                    window_size=window, show_ui=not args.no_ui, script=script)
    viewer.target_frames, viewer.target_seconds = args.target_frames, args.target_seconds
    for option in ("reuse", "foveation"):
        if trace[option]:
            viewer.set_graph_option(option, trace[option])
    if trace["decision"]:
        viewer.graph.update_pass("Decision", trace["decision"])
    try:
        if args.record:
            viewer.start_recording()
        viewer.run(args.frames, args.screenshot)
        if args.screenshot:
            print(f"wrote {args.screenshot}")
        if args.record:
            print(f"wrote {viewer.save_camera_path(args.record)}")
    finally:
        viewer.close()
    return 0


def builder_name_of(spec) -> bool:
    """Whether --graph names a ready-made graph (checked before the viewer extra is imported)."""
    from ..graphs import COMMAND_LINE_GRAPHS

    return spec is None or spec in COMMAND_LINE_GRAPHS
