"""`rayvr check [SCENE] [--masks DIR]`: render the scene with every ready-made graph (hybrid,
hybrid_taa, path_traced) at every effect level at a tiny size, and print per pass and output
texture how many non-finite values it wrote, plus the loader's warnings.

Exit code 0: every value finite; 1: some pass wrote NaN or Inf, or a configuration failed to
compile or render; 2: bad input (the scene file, an option). With --masks DIR, a PNG per pass
output that had any (white where a texel is not finite, views side by side) goes into DIR.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from .options import MAX_VIEWS, integer, load_scene_arg, parse_size, views_count


def register(sub) -> None:
    p = sub.add_parser("check", help="render with every graph and effect; count non-finite values per pass")
    p.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: the Cornell box)")
    p.add_argument("--size", default="32x32", help="per-view size WIDTHxHEIGHT (default 32x32)")
    p.add_argument("--views", type=views_count(), default=2, help=f"view count, 1 to {MAX_VIEWS} (default 2)")
    p.add_argument("--frames", type=integer("--frames", 1, 1000), default=2,
                   help="frames per configuration, 1 to 1000 (default 2: history passes run twice)")
    p.add_argument("--masks", metavar="DIR", help="write a PNG mask of the non-finite texels per pass output here")
    p.set_defaults(func=run)


def mask_name(finding) -> str:
    """'hybrid_RASTER-Direct-direct.png': configuration, pass and pin."""
    return f"{finding.config.replace(' ', '_')}-{finding.pass_name}-{finding.pin}.png"


def run(args) -> int:
    from ..check import run_check
    from ..fileio import atomic_group, check_writable, write_image

    size = parse_size(args.size, views=args.views)
    masks = Path(args.masks) if args.masks else None
    if masks is not None:
        check_writable(masks, "--masks", folder=True)
    scene = load_scene_arg(args.scene, print_warnings=False)
    print(f"check {scene.name}: {args.views} view(s) of {size[0]}x{size[1]}, {args.frames} frame(s) per configuration")
    findings, failures = run_check(scene, size, args.views, args.frames, progress=sys.stderr.isatty())
    configs = list(dict.fromkeys(f.config for f in findings))
    for config in configs:
        rows = [f for f in findings if f.config == config]
        bad = sum(f.nonfinite for f in rows)
        print(f"{config}: {'ok' if not bad else f'{bad} non-finite values'}")
        passes = list(dict.fromkeys(f.pass_name for f in rows))
        for name in passes:
            pins = ", ".join(f"{f.pin} {f.nonfinite}" for f in rows if f.pass_name == name)
            print(f"  {name}: {pins}")
    for failure in failures:
        print(f"{failure.config}: failed: {failure.error}")
    print(f"warnings: {len(scene.warnings)}")
    for line in scene.warnings:
        print(f"  {line}")
    bad = [f for f in findings if f.nonfinite]
    with_masks = [f for f in bad if f.mask is not None]
    if with_masks and masks is not None:
        with atomic_group():
            for f in with_masks:
                image = np.concatenate(list(f.mask), axis=1).astype(np.uint8) * 255
                write_image(masks / mask_name(f), np.repeat(image[..., None], 3, axis=-1))
        print(f"wrote {len(with_masks)} mask(s) into {masks}")
    elif with_masks:
        print("give --masks DIR to write where the non-finite texels are")
    return 1 if bad or failures else 0
