"""`rayvr graph show FILE`: compile a saved graph (.py or .json) and print its report, DOT or picture."""
from __future__ import annotations

import json

from .options import MAX_VIEWS, load_scene_arg, parse_size, views_count


def register(sub) -> None:
    p = sub.add_parser("graph", help="inspect saved render graphs")
    gsub = p.add_subparsers(dest="graph_command", metavar="ACTION")
    show = gsub.add_parser("show", help="compile a saved graph and print its report")
    show.add_argument("file", help="graph file: .py script (runs it) or .json (runs no code)")
    show.add_argument("--size", default="128x128", help="per-view size WxH to compile at (default 128x128)")
    show.add_argument("--views", type=views_count(), default=2,
                      help=f"view count, 1 to {MAX_VIEWS} (default 2: stereo)")
    show.add_argument("--scene", help="glTF file or built-in scene name (e.g. cornell_box) the passes "
                      "compile against; default none")
    show.add_argument("--dot", action="store_true", help="print the graph as Graphviz DOT instead")
    show.add_argument("--png", metavar="OUT", help="also draw the graph to OUT (.png/.svg/.pdf; checked for "
                      "writability before anything is compiled)")
    show.add_argument("--json", action="store_true", help="print the report as JSON")
    show.set_defaults(func=run_show)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


def run_show(args) -> int:
    """Load the graph (and scene), compile it, print the report or DOT; the picture is drawn
    last, so a command that fails writes nothing."""
    from ..fileio import check_writable
    from ..rendergraph.graph import RenderGraph
    from ..rendergraph.picture import picture_format

    size = parse_size(args.size, views=args.views)
    if args.png:
        picture_format(args.png)
        check_writable(args.png, "--png")
    graph = RenderGraph.load(args.file)
    if args.dot:
        text = graph.to_dot()
    else:
        scene = gpu_scene = None
        extra = []
        if args.scene:
            from ..gpu import get_context
            from ..scene import GpuScene

            scene = load_scene_arg(args.scene)
            gpu_scene = GpuScene(get_context(), scene)
            extra.append(gpu_scene.report())
        report = graph.compile(scene=scene, size=size, views=args.views, gpu_scene=gpu_scene,
                               extra_report=extra).report()
        text = (json.dumps(report.as_dict(), indent=2, default=str) if args.json else str(report)) + "\n"
    if args.png:
        graph.save_picture(args.png)
    print(text, end="")
    if args.png and not args.dot:
        print(f"picture: {args.png}")
    return 0
