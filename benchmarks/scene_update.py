"""CPU cost of the GPU scene's per-frame work while a head walks through a scene of many
instances: `GpuScene.update(origin)` (instances, TLAS, lights, render-space origin) plus the
views' restart key and packing, per frame. The GPU work is not timed (this is the CPU side of a
frame). Run it against an older commit to compare: the scene and the walk are built here from
the public API only.
"""
from __future__ import annotations

import time

import numpy as np

from rayvr.gpu import get_context

WALK_SPEED = 1.4       # m/s, a brisk walk
FRAME_S = 1 / 90       # 90 Hz


def add_arguments(parser) -> None:
    parser.add_argument("--instances", type=int, default=10_000)
    parser.add_argument("--frames", type=int, default=300, help="timed frames (quick: 20)")
    parser.add_argument("--lights", type=int, default=4)


def instanced_scene(count: int, lights: int):
    """`count` boxes on a square grid of 0.5 m spacing, one mesh instanced, a few point lights."""
    from rayvr.scene import Light, Material, Mesh, Scene

    s = Scene(f"boxes{count}")
    s.add_material(Material("Box", base_color=(0.8, 0.8, 0.8, 1.0), metallic=0.0))
    v = np.array([[x, y, z] for x in (-0.1, 0.1) for y in (0.0, 0.2) for z in (-0.1, 0.1)], np.float32)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.uint32)
    mesh = s.add_mesh(Mesh("box", v, f, np.uint32(0)))
    side = int(np.ceil(np.sqrt(count)))
    for i in range(count):
        t = np.eye(4)
        t[:3, 3] = (0.5 * (i % side), 0.0, -0.5 * (i // side))
        s.add_instance(mesh, t, f"box{i}")
    for k in range(lights):
        s.lights.append(Light("point", position=(k * 2.0, 3.0, -k * 2.0), intensity=10.0))
    return s


def run(args) -> dict:
    from rayvr.scene import GpuScene
    from rayvr.xr.cameras import default_views
    from rayvr.xr.views import Pose, View, ViewSet

    frames = 20 if args.quick else args.frames
    count = 1000 if args.quick else args.instances
    gpu = get_context()
    scene = instanced_scene(count, args.lights)
    t0 = time.perf_counter()
    gs = GpuScene(gpu, scene)
    build_ms = (time.perf_counter() - t0) * 1e3
    base = default_views(scene, 2, (64, 64))
    step = np.array([0.0, 0.0, -WALK_SPEED * FRAME_S])
    times = np.empty(frames)
    for k in range(frames + 5):
        views = ViewSet([View(Pose(v.pose.position + k * step, v.pose.orientation), v.fov, v.width, v.height)
                         for v in base])
        gpu.gl.finish()
        t0 = time.perf_counter()
        origin = views.origin()
        gs.update(origin)
        key = views.restart_key(origin) if hasattr(views, "restart_key") else None
        views.pack(origin, k, 0)
        if k >= 5:
            times[k - 5] = (time.perf_counter() - t0) * 1e3
    gpu.gl.finish()
    gs.release()
    del key
    return {"columns": ["instances", "lights", "frames", "build_ms", "update_ms_mean", "update_ms_median",
                        "update_ms_p95"],
            "rows": [[count, args.lights, frames, round(build_ms, 1), round(float(times.mean()), 4),
                      round(float(np.median(times)), 4), round(float(np.percentile(times, 95)), 4)]],
            "notes": [f"walk at {WALK_SPEED} m/s, {1 / FRAME_S:.0f} Hz; CPU ms per frame of GpuScene.update "
                      f"+ the views' restart key and packing; GPU work not timed"]}
