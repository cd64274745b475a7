"""BVH build: time, SAH cost next to a binned-SAH reference build of the same triangles, and
GPU bytes per triangle.

Each scene's instances are flattened to world-space triangles and built as one BVH (the
target's measure; GpuScene's own per-mesh BLAS builds are timed too), with the
builder GpuScene picks for that size ('auto': binned SAH up to 100k triangles, LBVH beyond), and
again with the binned-SAH reference (16 bins, 3 axes; `--ref-max` skips it for huge inputs).
SAH cost: traversal steps + triangle tests per ray, relative to the root box (C_trav = C_tri = 1).
Targets (H100 machine): 1.04M triangles <= 200 ms, 2.7M <= 500 ms, for the layout that is traced
("bvh4", GpuScene's default): with --method gpu the GPU build plus the GPU collapse to "bvh4".

Scenes: glTF paths (a folder means the .gltf/.glb inside it; relative paths are also looked up
under ../shared/scenes and shared/scenes), built-in names (cornell_box), or generated:N (a
displaced-grid terrain of about N triangles).
"""
from __future__ import annotations

import dataclasses
import os
import time
from pathlib import Path

import numpy as np

DEFAULT_SCENES = "tauray/test.glb,khronos/MetalRoughSpheresNoTextures,khronos/ToyCar,generated:2700000"
QUICK_SCENES = "cornell_box,generated:20000"
TARGETS_MS = [(1_040_000, 200.0), (2_700_000, 500.0)]
REPO = Path(__file__).resolve().parents[1]


def add_arguments(parser) -> None:
    parser.add_argument("--scenes", default=None,
                        help=f"comma-separated scenes (default {DEFAULT_SCENES}; quick: {QUICK_SCENES})")
    parser.add_argument("--method", default="auto", choices=["auto", "lbvh", "sah", "gpu"],
                        help="builder under test (gpu: the compute-shader LBVH of rayvr.scene.bvh_gpu)")
    parser.add_argument("--no-gpu-build", action="store_true", help="skip the gpu_build_ms column")
    parser.add_argument("--repeat", type=int, default=3, help="builds per scene, the fastest counts (quick: 1)")
    parser.add_argument("--ref-max", type=int, default=3_000_000,
                        help="largest triangle count given a binned-SAH reference build")
    parser.add_argument("--no-gpu-scene", action="store_true", help="skip uploading a GpuScene (bytes/triangle)")
    parser.add_argument("--threads", type=int, default=0, help="build threads (default: all cores)")
    parser.add_argument("--bvh-layout", default=None,
                        help="GpuScene's layout for gpu_bytes_per_tri and gpu_scene_blas_ms (default: its default)")


def generated_mesh(n_triangles: int):
    """A displaced grid terrain with about n_triangles triangles (positions, indices)."""
    n = max(2, int(round(np.sqrt(n_triangles / 2))) + 1)
    x, z = np.meshgrid(np.linspace(-50, 50, n), np.linspace(-50, 50, n))
    y = 3 * np.sin(x * 0.3) * np.cos(z * 0.25) + 0.5 * np.sin(x * 2.1 + z * 1.7)
    pos = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype(np.float32)
    i = np.arange((n - 1) * (n - 1))
    r, c = i // (n - 1), i % (n - 1)
    a = r * n + c
    quads = np.stack([a, a + n, a + 1, a + 1, a + n, a + n + 1], axis=1).reshape(-1, 3)
    return pos, quads.astype(np.uint32)


def resolve_scene(spec: str):
    """A Scene from generated:N, or from a path, folder or built-in name as
    `rayvr.cli.options.load_scene_arg` takes them, a relative path also found under the shared
    scenes."""
    from rayvr.cli.options import load_scene_arg
    from rayvr.scene import Material, Scene

    if spec.startswith("generated:"):
        pos, idx = generated_mesh(int(float(spec.split(":", 1)[1])))
        s = Scene(f"generated {len(idx)}")
        s.add_material(Material("Terrain", metallic=0.0))
        s.add_object("Terrain", pos, idx, 0)
        return s
    for base in (Path.cwd(), REPO, REPO.parent / "shared" / "scenes", REPO / "shared" / "scenes",
                 REPO.parent / "shared"):
        if (base / spec).exists():
            return load_scene_arg(str(base / spec), option="--scenes")
    return load_scene_arg(spec, option="--scenes")


def world_triangles(scene) -> np.ndarray:
    parts = []
    for inst in scene.instances:
        t = scene.meshes[inst.mesh].triangles().astype(np.float64)
        parts.append((t @ inst.transform[:3, :3].T + inst.transform[:3, 3]).astype(np.float32))
    return np.concatenate(parts) if parts else np.zeros((0, 3, 3), np.float32)


def _blank(v):
    """A table cell: '' for a value not measured."""
    return v if v is not None else ""


def _timed_build(lo, hi, method, repeat, threads=None):
    from rayvr.scene.bvh import build

    best, b = float("inf"), None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        b = build(lo, hi, method=method, progress=False, threads=threads or None)
        best = min(best, time.perf_counter() - t0)
    return b, best * 1e3


def _timed_gpu_build(tris, repeat):
    """GPU LBVH: upload + all kernels + glFinish (the fastest of `repeat`; the first build, which
    also compiles the kernels and allocates scratch, is reported apart), the same plus the GPU
    collapse to "bvh4" and to "bvh8" (fastest of `repeat` each), then the read-back of the BVH2.
    Returns the BVH2, its GPU-collapsed WideBvh and Bvh8 and the times in ms: build, build +
    collapse to bvh4, to bvh8, first build, read-back."""
    from rayvr.gpu import get_context
    from rayvr.scene.bvh_gpu import builder_for

    gpu = get_context()
    t0 = time.perf_counter()
    builder = builder_for(gpu)
    builder.collapse_bvh4(builder.build(tris))
    builder.collapse_bvh8(builder.build(tris))
    gpu.gl.finish()
    first = time.perf_counter() - t0

    def fastest(collapse):
        best = float("inf")
        for _ in range(max(1, repeat)):
            t0 = time.perf_counter()
            g = builder.build(tris)
            wide = collapse(g)
            gpu.gl.finish()
            best = min(best, time.perf_counter() - t0)
        return g, wide, best * 1e3

    _, _, build_ms = fastest(lambda g: None)
    _, _, bvh4_ms = fastest(builder.collapse_bvh4)
    g, g8, bvh8_ms = fastest(builder.collapse_bvh8)
    t0 = time.perf_counter()
    b = g.to_bvh()
    readback = time.perf_counter() - t0
    w8 = g8.to_bvh8(b)                              # its links, before the bvh4 collapse reuses the buffers
    w4 = builder.collapse_bvh4(g).to_wide(b)        # of the same BVH2
    return b, w4, w8, build_ms, bvh4_ms, bvh8_ms, first * 1e3, readback * 1e3


def run(args) -> dict:
    from rayvr.gpu import get_context
    from rayvr.scene import GpuScene
    from rayvr.scene import bvh8, bvh_wide
    from rayvr.scene.bvh import NODE_BYTES, triangle_bounds
    from rayvr.scene.bvh_gpu import MIN_TRIANGLES

    specs = (args.scenes or (QUICK_SCENES if args.quick else DEFAULT_SCENES)).split(",")
    repeat = 1 if args.quick else args.repeat
    rows, notes = [], []
    for spec in specs:
        t0 = time.perf_counter()
        scene = resolve_scene(spec.strip())
        load_s = time.perf_counter() - t0
        tris = world_triangles(scene)
        n = len(tris)
        t0 = time.perf_counter()
        lo, hi = triangle_bounds(tris)
        bounds_ms = (time.perf_counter() - t0) * 1e3
        gpu_ms = gpu4_ms = gpu8_ms = gpu_first_ms = gpu_read_ms = gpu_cost = gpu4 = gpu8 = None
        if n >= MIN_TRIANGLES and (args.method == "gpu" or not args.no_gpu_build):
            gb, gpu4, gpu8, gpu_ms, gpu4_ms, gpu8_ms, gpu_first_ms, gpu_read_ms = _timed_gpu_build(tris, repeat)
            gpu_cost = gb.sah_cost()
        traced_ms = None     # the time meets_target counts
        if args.method == "gpu" and gpu_ms is not None:
            b, build_ms, bounds_ms, traced_ms = gb, gpu_ms, 0.0, gpu4_ms
        else:
            b, build_ms = _timed_build(lo, hi, args.method, repeat, args.threads)
        traced_ms = build_ms + bounds_ms if traced_ms is None else traced_ms
        cost = b.sah_cost(lo, hi)
        t0 = time.perf_counter()
        wide = bvh_wide.collapse(b)
        collapse_ms = (time.perf_counter() - t0) * 1e3
        gpu4_vs_cpu = gpu4.sah_cost() / wide.sah_cost() if gpu4 is not None and gpu4.source is b else None
        t0 = time.perf_counter()
        wide8 = bvh8.collapse(b)
        wide8.nodes
        collapse8_ms = (time.perf_counter() - t0) * 1e3
        gpu8_vs_cpu = gpu8.sah_cost() / wide8.sah_cost() if gpu8 is not None and gpu8.source is b else None
        quantized = dataclasses.replace(wide, quantized=True)
        t0 = time.perf_counter()
        quantized.nodes
        quantize_ms = (time.perf_counter() - t0) * 1e3
        ref_ms = ref_cost = None
        if n <= args.ref_max:
            ref, ref_ms = _timed_build(lo, hi, "sah", 1)
            ref_cost = ref.sah_cost(lo, hi)
        target = next((ms for count, ms in TARGETS_MS if abs(n - count) / count < 0.1), None)
        gpu_bpt = blas_ms = None
        if not args.no_gpu_scene:
            try:
                gs = GpuScene(get_context(), scene, progress=False, bvh_layout=args.bvh_layout,
                              bvh_method="gpu" if args.method == "gpu" else "auto")
                gpu_bpt = gs.report()["geometry_bytes_per_triangle"]
                blas_ms = gs.timings["blas_build_ms"]
                gs.release()
            except Exception as exc:   # e.g. llvmpipe's 128 MB SSBO limit
                notes.append(f"{spec}: no GpuScene ({exc})")
        rows.append({
            "scene": spec, "triangles": n, "method": b.method, "build_ms": build_ms + bounds_ms,
            "target_ms": _blank(target),
            "meets_target": ("yes" if traced_ms <= target else "no") if target else "",
            "sah_cost": cost, "ref_sah_cost": _blank(ref_cost),
            "sah_vs_ref": cost / ref_cost if ref_cost else "", "ref_build_ms": _blank(ref_ms),
            "bvh_bytes_per_tri": (b.node_count * NODE_BYTES + n * 48) / max(n, 1),
            "bvh4_nodes": wide.node_count, "bvh4_collapse_ms": collapse_ms,
            "bvh4_bytes_per_tri": (wide.nbytes + n * 48) / max(n, 1),
            "bvh4q_bytes_per_tri": (wide.node_count * bvh_wide.QUANTIZED_NODE_BYTES + n * 48) / max(n, 1),
            "bvh4q_pack_ms": quantize_ms,
            "bvh8_nodes": wide8.node_count, "bvh8_collapse_ms": collapse8_ms,
            "bvh8_bytes_per_tri": (wide8.nbytes + n * 48) / max(n, 1),
            "bvh8_node_visits_vs_bvh4": wide8.sah_cost(c_tri=0) / wide.sah_cost(c_tri=0),
            "gpu_bvh8_ms": _blank(gpu8_ms), "gpu_bvh8_sah_vs_cpu_bvh8": _blank(gpu8_vs_cpu),
            "gpu_bytes_per_tri": _blank(gpu_bpt), "load_s": load_s,
            "meshes": len(scene.meshes), "gpu_scene_blas_ms": _blank(blas_ms),
            "gpu_build_ms": _blank(gpu_ms), "gpu_bvh4_ms": _blank(gpu4_ms),
            "gpu_bvh4_nodes": _blank(gpu4 and gpu4.node_count), "gpu_bvh4_sah_vs_cpu_bvh4": _blank(gpu4_vs_cpu),
            "gpu_first_build_ms": _blank(gpu_first_ms),
            "gpu_readback_ms": _blank(gpu_read_ms), "gpu_sah_vs_ref": gpu_cost / ref_cost if gpu_cost and ref_cost else "",
        })
    notes.append(f"build_ms: triangle boxes + build + GPU node layout (fastest of --repeat); numpy, LBVH above "
                 f"200k triangles on {args.threads or os.cpu_count()} threads")
    notes.append("gpu_build_ms: GPU LBVH (compute shaders, 30-bit Morton codes, radix sort, 3 rounds of tree rotations, "
                 "leaves <= 4): triangle "
                 "upload + all kernels + glFinish, fastest of --repeat; gpu_bvh4_ms: the same build plus the GPU "
                 "collapse to the traced 'bvh4' layout (greedy, one dispatch per BVH4 level) + glFinish, fastest of "
                 "--repeat; gpu_bvh4_sah_vs_cpu_bvh4: its SAH cost over the CPU's SAH-optimal collapse of the same "
                 "BVH2 (--method gpu); gpu_first_build_ms: the first build and collapse (kernel compile + scratch "
                 "allocation); gpu_readback_ms: copying nodes and order back to a CPU Bvh (not needed to trace); "
                 "gpu_bvh8_ms: the same build plus the GPU collapse to 'bvh8' (greedy, direction slots, 8-bit boxes, "
                 "the leaves' triangles copied into its order) + glFinish; gpu_bvh8_sah_vs_cpu_bvh8: its SAH cost "
                 "over the CPU's SAH-optimal 8-wide collapse")
    notes.append("meets_target: build_ms against target_ms, except with --method gpu: gpu_bvh4_ms, the GPU build "
                 "and GPU collapse of the layout GpuScene traces by default ('bvh4')")
    notes.append("gpu_scene_blas_ms: what GpuScene spends on its per-mesh BLAS builds and uploads (meshes in "
                 "parallel; SAH for meshes up to 100k triangles)")
    notes.append("bvh_bytes_per_tri: 64-byte BVH2 nodes + 48-byte BVH-ordered triangles; bvh4_*: the same BVH "
                 "collapsed to 112-byte BVH4 nodes on the CPU (bvh_wide.collapse, SAH-optimal, timed apart); bvh4q_*: the same collapse "
                 "quantised to 64-byte nodes (bvh4q_pack_ms: packing without the collapse); bvh8_*: the compressed "
                 "8-wide collapse, 80-byte nodes (bvh8_collapse_ms: collapse + packing; bvh8_node_visits_vs_bvh4: "
                 "its SAH node term over bvh4's); gpu_bytes_per_tri adds "
                 "vertices, indices, materials, instances (all scene buffers, GpuScene's default layout)")
    cols = ["scene", "triangles", "method", "build_ms", "target_ms", "meets_target", "sah_cost", "ref_sah_cost",
            "sah_vs_ref", "ref_build_ms", "gpu_build_ms", "gpu_bvh4_ms", "gpu_bvh4_nodes", "gpu_bvh4_sah_vs_cpu_bvh4",
            "gpu_first_build_ms", "gpu_readback_ms", "gpu_sah_vs_ref",
            "bvh_bytes_per_tri", "bvh4_nodes", "bvh4_bytes_per_tri", "bvh4_collapse_ms",
            "bvh4q_bytes_per_tri", "bvh4q_pack_ms", "bvh8_nodes", "bvh8_bytes_per_tri", "bvh8_collapse_ms",
            "bvh8_node_visits_vs_bvh4", "gpu_bvh8_ms", "gpu_bvh8_sah_vs_cpu_bvh8", "gpu_bytes_per_tri", "meshes",
            "gpu_scene_blas_ms",
            "load_s"]
    return {"columns": cols, "rows": rows, "notes": notes}
