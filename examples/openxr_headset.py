"""Run the hybrid graph on a real headset through the machine's OpenXR runtime.

    python examples/openxr_headset.py [SCENE.gltf] [--frames N] [--validation] < /dev/null

SteamVR (Linux desktop, GLX: set RAYVR_GL_BACKEND=default with DISPLAY set) or Monado (headless EGL, the default
context) must be the active OpenXR runtime (XR_RUNTIME_JSON or /etc/xdg/openxr/1/active_runtime.json).
For Monado's headless null compositor: XR_RUNTIME_JSON=<build>/openxr_monado-dev.json
XRT_COMPOSITOR_NULL=1 SIMULATED_ENABLE=1. Keep stdin on /dev/null: some Monado builds close fd 0
when GL swapchains are destroyed (the sink puts /dev/null back on fd 0 when that happens). Without
a runtime this prints "no OpenXR runtime: install SteamVR or Monado and make it the active runtime
(set XR_RUNTIME_JSON ...)" and exits with code 2; Ctrl-C ends the session cleanly (exit code 130).
"""
import argparse
import sys

import rayvr as rv
from rayvr.xr.cameras import camera_pose


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", help="glTF file (default: the built-in Cornell box)")
    ap.add_argument("--frames", type=int, default=None, help="ask the runtime to end after N frames")
    ap.add_argument("--validation", action="store_true", help="enable the Khronos core validation layer")
    ap.add_argument("--space", default="stage", choices=("stage", "local"))
    args = ap.parse_args()

    scene = rv.load_scene(args.scene) if args.scene else rv.scenes.cornell_box()
    # Put the tracking space's origin (the floor under the user) below the scene's camera.
    cam, _ = camera_pose(scene)
    world = rv.xr.Pose([cam.position[0], cam.position[1] - 1.6, cam.position[2]], cam.orientation)
    sink = rv.xr.OpenXRSink(reference_space=args.space, world_pose=world, frames=args.frames,
                            validation=args.validation)
    try:
        with rv.Renderer(scene, rv.graphs.hybrid(), sink=sink) as r:
            for frame in r.frames():
                pass
            print(r.profile())
        print(f"{sink.frame_count} frames; session states: {[s.name for s in sink.lifecycle.history]}")
    except rv.RayvrError as exc:
        print(f"openxr_headset: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:   # the Renderer's close() has ended the session
        print("openxr_headset: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
