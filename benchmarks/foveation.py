"""Foveation (hybrid(foveation='fixed')): stereo frames with and without a ray budget that falls
with eccentricity from each view's centre, through the hybrid graph.

Rays per frame (GPU counters of the ray passes), GPU ms per frame, and the displayed image's FLIP
against a converged path-traced reference: over the whole image, within the foveal radius (the
central 10 degrees) and weighted by eccentricity. Target (tauray, 2x1440x1600): >= 2x fewer rays
with fixed foveation, foveal FLIP within 5% of no foveation.
"""
from __future__ import annotations

from rayvr.cli.options import load_scene_arg, parse_size

from ._decision import Progress, add_common_arguments, cells, ms, settings


def add_arguments(parser) -> None:
    add_common_arguments(parser)
    parser.add_argument("--size", default="1440x1600", help="per-eye WIDTHxHEIGHT (default 1440x1600)")
    parser.add_argument("--fov", type=float, default=None,
                        help="vertical field of view in degrees (default: the scene camera's); a headset's is ~100")
    parser.add_argument("--foveal-radius", type=float, default=None, help="degrees (default the pass's, 5)")
    parser.add_argument("--periphery-share", type=float, default=None, help="(default the pass's, 0.25)")


def _views(scene, size, fov):
    from rayvr.xr.cameras import camera_pose, default_views, stereo_views
    from rayvr.xr.views import Fov

    if fov is None:
        return default_views(scene, 2, size)
    return stereo_views(camera_pose(scene)[0], 0.063, Fov.symmetric(fov, size[0] / size[1]),
                        Fov.symmetric(fov, size[0] / size[1]), size)


def run(args) -> dict:
    import rayvr as rv

    s = settings(args)
    size = (48, 48) if args.quick else parse_size(args.size, views=2)
    scene = load_scene_arg(args.scene)
    view_set = _views(scene, size, args.fov)
    props = {k: v for k, v in (("foveal_radius_deg", args.foveal_radius), ("periphery_share", args.periphery_share))
             if v is not None}
    out = {}
    with Progress(s, [(view_set, 2)], "foveation") as progress:
        ref = progress.reference(scene, view_set)
        for fov in (None, "fixed"):
            g = rv.graphs.hybrid(preset=args.preset, foveation=fov, decision=props if fov else None)
            out[fov] = progress.measure(f"foveation {fov or 'none'}", scene, view_set, g, ref, args.ppd)
    base = out[None]
    rows = []
    for fov, row in out.items():
        fewer = sum(base["rays"]) / max(sum(row["rays"]), 1)
        foveal = row["flip_fovea"] / max(base["flip_fovea"], 1e-12)
        rows.append([fov or "none", f"2x{size[0]}x{size[1]}", *cells(row), round(fewer, 3),
                     round(ms(row) / ms(base), 3), round(foveal, 3),
                     ("yes" if fewer >= 2.0 and foveal <= 1.05 else "NO") if fov else ""])
    return {
        "columns": ["foveation", "size", "wall_ms", "gpu_ms", "rays_total", "flip", "flip_fovea", "flip_ecc",
                    "fewer_rays_x", "ms/none", "flip_fovea/none", "meets_target"],
        "rows": rows,
        "notes": [f"scene {args.scene}, hybrid preset {args.preset}, fall-off {props or 'the defaults'}",
                  f"FLIP of the displayed image after {s['judged']} still frames against a path-traced reference "
                  f"of {s['ref_frames']} x {s['ref_spp']} spp; fovea: within 5 degrees of each view's centre",
                  "target: >= 2x fewer rays, flip_fovea <= 1.05x no foveation"],
    }
