"""Run the hybrid graph on a simulated Valve Index and write what the "display" was given.

    python examples/headset_sim.py [SCENE.gltf] --preset index --trajectory turn --frames 30 --out out/headset

Per-eye and side-by-side PNGs (and a video with --video) land in --out; the compositor's
statistics (on-time / reprojected / dropped frames, motion-to-photon latency) are printed.
The frame time each frame reports to the compositor is the graph's measured GPU time.
"""
import argparse
import json

import rayvr as rv
from rayvr.xr.cameras import camera_pose


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", help="glTF file (default: the built-in Cornell box)")
    ap.add_argument("--preset", default="index", choices=sorted(rv.xr.PRESETS))
    ap.add_argument("--refresh", type=float, default=None, help="Hz (default: the preset's)")
    ap.add_argument("--trajectory", default="turn", help="still, turn, walk or a JSON pose log")
    ap.add_argument("--size", type=int, nargs=2, default=(128, 128), metavar=("W", "H"),
                    help="per-eye pixels (default 128 128; the preset's real size is slow on llvmpipe)")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--out", default="out/headset")
    ap.add_argument("--video", action="store_true", help="also write headset.mp4 (or .gif)")
    args = ap.parse_args()

    scene = rv.load_scene(args.scene) if args.scene else rv.scenes.cornell_box()
    start, _ = camera_pose(scene)
    headset = rv.xr.SimulatedHeadset(preset=args.preset, refresh_hz=args.refresh, trajectory=args.trajectory,
                                     size=tuple(args.size), start_pose=start, record_dir=args.out,
                                     video=args.video, frames=args.frames)
    with rv.Renderer(scene, rv.graphs.hybrid(), sink=headset) as r:
        for _ in r.frames():
            pass
        print(r.profile())
    print(json.dumps(headset.stats(), indent=2))
    print(f"frames written to {args.out}/")


if __name__ == "__main__":
    main()
