"""Render a light field for a Looking Glass display and write it as a quilt PNG.

    python examples/lightfield_quilt.py [SCENE.gltf] --display portrait --view-scale 0.25 --out out/quilt.png

The views are a horizontal row of sheared (off-axis) cameras converging on the focal plane at
the scene's centre, spanning the display's view cone (`rayvr.xr.quilt.quilt_views`, as
`rayvr render --quilt` uses); the quilt is composed on the GPU (view 0 bottom-left) and saved with
Looking Glass's `_qs{cols}x{rows}a{aspect}` suffix.
"""
import argparse

import rayvr as rv
from rayvr.xr.quilt import compose_quilt, looking_glass, quilt_filename, quilt_views, write_quilt_png


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", help="glTF file (default: the built-in Cornell box)")
    ap.add_argument("--display", default="portrait", help="Looking Glass model (portrait, go, 16in_landscape, ...)")
    ap.add_argument("--view-scale", type=float, default=0.1,
                    help="fraction of the display's per-view size to render (default 0.1: fast on llvmpipe)")
    ap.add_argument("--cone", type=float, default=40.0, help="view cone in degrees (default 40)")
    ap.add_argument("--focus", type=float, default=None, help="focal distance in metres (default: scene centre)")
    ap.add_argument("--out", default="out/quilt.png")
    args = ap.parse_args()

    layout = looking_glass(args.display)
    scene = rv.load_scene(args.scene) if args.scene else rv.scenes.cornell_box()
    vw, vh = (max(8, round(s * args.view_scale)) for s in layout.view_size)
    views = quilt_views(scene, layout.cols, layout.rows, (vw, vh), args.cone, args.focus)
    with rv.Renderer(scene, rv.graphs.hybrid(), views=views) as r:
        r.render()
        quilt = compose_quilt(r.gl, r.output_texture(), layout.cols, layout.rows)
        path = write_quilt_png(quilt, quilt_filename(args.out, layout.cols, layout.rows, layout.aspect))
    print(f"{layout.views} views of {vw}x{vh} -> {path}")


if __name__ == "__main__":
    main()
