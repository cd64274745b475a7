"""Run the hybrid graph in stereo on the simulated headset, switching a material's effect while
it runs, and print per-pass timings for each effect.

    python examples/hybrid_effects.py                       # built-in Cornell box, 2 x 128x128
    python examples/hybrid_effects.py scene.glb --material Floor --size 1440x1600 --frames 30
"""
from __future__ import annotations

import argparse

import rayvr as rv
from rayvr.cli.options import load_scene_arg, parse_size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: Cornell box)")
    ap.add_argument("--material", default=None, help="material to switch (default: the first one)")
    ap.add_argument("--size", default="128x128", help="per-eye size (default 128x128)")
    ap.add_argument("--frames", type=int, default=3, help="frames per effect (default 3)")
    ap.add_argument("--record", default=None, help="folder for the headset's eye images")
    args = ap.parse_args()

    scene = load_scene_arg(args.scene)
    name = args.material or next(iter(scene.materials)).name
    effects = [rv.Effect.RASTER, rv.Effect.SHADOWS, rv.Effect.REFLECTIONS]
    headset = rv.xr.SimulatedHeadset(preset="index", size=parse_size(args.size),
                                     frames=args.frames * len(effects), record_dir=args.record)
    print(f"{scene}: switching '{name}' through {', '.join(e.name for e in effects)}")
    with rv.Renderer(scene, rv.graphs.hybrid(), sink=headset) as r:
        for frame in r.frames():
            step = frame.index // args.frames
            if frame.index % args.frames == 0:
                if step > 0:   # timings of the effect that just finished
                    print(f"\n--- {name} = {effects[step - 1].name} ---\n{r.profile()}")
                frame.materials[name].effect = effects[step]
        print(f"\n--- {name} = {effects[-1].name} ---\n{r.profile()}")
        print(f"\ngraph compiled {r.compiles} times (once per distinct set of used effects)")
        print(r.report())
    print(headset.stats())


if __name__ == "__main__":
    main()
