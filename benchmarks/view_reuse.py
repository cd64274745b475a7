"""View reuse (hybrid(reuse='views')): stereo and a 64-view camera grid with and without reusing
the source views' shaded light, through the hybrid graph.

Per view count: GPU ms per frame (timer queries; wall time where there are none), rays the ray
passes traced per view in the last frame (GPU counters: the first view's, and the mean of the
others against it), and the displayed image's FLIP against a converged path-traced reference
(also within the foveal radius and weighted by eccentricity), after `--judged-frames` still
frames. Targets: stereo 2x1440x1600, the second eye's rays <= 0.3x the first's with FLIP within 5%
of independent eyes; 64 views of 512x683, GPU ms <= 0.5x independent views with FLIP within 5%.
"""
from __future__ import annotations

from rayvr.cli.options import load_scene_arg, parse_size

from ._dispatches import dispatch_cell
from ._decision import Progress, add_common_arguments, cells, ms, passes_cell, settings

TARGETS = {2: "rays_other/first <= 0.3, flip <= 1.05x", 64: "gpu <= 0.5x, flip <= 1.05x"}


def add_arguments(parser) -> None:
    add_common_arguments(parser)
    parser.add_argument("--views", default="2,64", help="comma-separated view counts (default 2,64)")
    parser.add_argument("--stereo-size", default="1440x1600", help="per-view size of 2 views (default 1440x1600)")
    parser.add_argument("--grid-size", default="512x683", help="per-view size of more views (default 512x683)")
    parser.add_argument("--lobe-fractions", default="",
                        help="comma-separated reuse_lobe_fraction values, a reuse row each beside the default's "
                             "(the Decision pass's: glossier lobes reused where wide against the eyes' parallax)")
    parser.add_argument("--variants", default="",
                        help="';'-separated reuse rows beside the default's, each comma-separated Pass.property=value "
                             "overrides of the reuse graph, e.g. 'Shadows.dispatch_mode=image;Decision.source_stride=3'")


def parse_variants(text: str) -> list[tuple[str, dict]]:
    """`--variants` as (label, {pass: {property: value}}) pairs; values are Python literals or words."""
    import ast

    out = []
    for part in (v.strip() for v in text.split(";")):
        if not part:
            continue
        props: dict = {}
        for item in part.split(","):
            key, sep, value = item.strip().partition("=")
            name, dot, prop = key.partition(".")
            if not sep or not dot:
                raise SystemExit(f"--variants: '{item.strip()}' is not Pass.property=value")
            try:
                value = ast.literal_eval(value)
            except (ValueError, SyntaxError):
                pass
            props.setdefault(name, {})[prop] = value
        out.append((f"views, {part}", props))
    return out


def _rows(n: int, size, out: dict, s: dict) -> list:
    """The table's rows of `n` views: each configuration against independent views (out[None])."""
    base, rows = out[None], []
    for reuse, row in out.items():
        first, others = row["rays"][0], row["rays"][1:]
        other_ratio = (sum(others) / len(others)) / max(first, 1)
        flip_ratio = row["flip"] / max(base["flip"], 1e-12)
        ok = other_ratio <= 0.3 if n == 2 else ms(row) <= 0.5 * ms(base)
        rows.append([n, f"{size[0]}x{size[1]}", reuse or "independent", *cells(row), first,
                     round(other_ratio, 3), round(ms(row) / ms(base), 3), round(flip_ratio, 3),
                     ("yes" if ok and flip_ratio <= 1.05 else "NO") if reuse and n in TARGETS else "",
                     passes_cell(row), *([dispatch_cell(row["dispatches"])] if s["dispatches"] else [])])
    return rows


def run(args) -> dict:
    import rayvr as rv
    from rayvr.xr.cameras import default_views

    s = settings(args)
    variants = [(f"views, lobe fraction {f:g}", {"Decision": {"reuse_lobe_fraction": f}})
                for f in (float(x) for x in args.lobe_fractions.split(",") if x.strip())]
    variants += parse_variants(args.variants)
    counts = [int(v) for v in args.views.split(",")]
    if args.quick and args.views == "2,64":
        counts = [2, 4]
    rows = []
    scene = load_scene_arg(args.scene)
    view_sets = {}
    for n in counts:
        size = parse_size(args.stereo_size if n <= 2 else args.grid_size, views=n)
        if args.quick:
            size = (32, 32) if n <= 2 else (16, 16)
        view_sets[n] = (size, default_views(scene, n, size))
    with Progress(s, [(v, 2 + len(variants)) for _, v in view_sets.values()], "view_reuse") as progress:
        for n, (size, view_set) in view_sets.items():
            ref = progress.reference(scene, view_set)
            out = {}
            for reuse in (None, "views"):
                out[reuse] = progress.measure(f"{n} views, {reuse or 'independent'}", scene, view_set,
                                              rv.graphs.hybrid(preset=args.preset, reuse=reuse), ref, args.ppd)
            for label, props in variants:
                g = rv.graphs.hybrid(preset=args.preset, reuse="views")
                for name, p in props.items():
                    g.update_pass(name, p)
                out[label] = progress.measure(f"{n} views, {label}", scene, view_set, g, ref, args.ppd)
            rows += _rows(n, size, out, s)
    return {
        "columns": ["views", "view_size", "config", "wall_ms", "gpu_ms", "rays_total", "flip", "flip_fovea",
                    "flip_ecc", "rays_first", "rays_other/first", "ms/independent", "flip/independent",
                    "meets_target", "passes_ms", *(["dispatch_ms"] if s["dispatches"] else [])],
        "rows": rows,
        "notes": [f"scene {args.scene}, hybrid preset {args.preset}; rays: GPU counters of the ray passes "
                  f"(shadow, reflection and path rays; not the G-buffer's or the probes') in the last timed frame",
                  f"FLIP of the displayed image after {s['judged']} still frames against a path-traced reference "
                  f"of {s['ref_frames']} x {s['ref_spp']} spp; fovea: within 5 degrees of each view's centre",
                  "targets: " + "; ".join(f"{n} views: {t}" for n, t in TARGETS.items())],
    }
