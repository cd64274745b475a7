"""Soak: many frames on the simulated headset while everything a session changes keeps changing;
live GL objects, process memory, GPU memory and frame time must stay flat.

    python -m benchmarks soak [--quick] [--frames 10000] [--effects-every 50] [--resize-every 500]

The Cornell box (plus a point light) renders with the hybrid graph on `SimulatedHeadset`:
every `--effects-every` frames every material moves to the next effect level (RASTER, SHADOWS,
REFLECTIONS, PATH_TRACED: the Renderer recompiles the graph each time the set of effects
changes); every frame the TallBox instance moves and the point light's intensity and position
change (GpuScene re-uploads them); every `--resize-every` frames the per-eye size changes, which
means a new Renderer and headset (rv.Renderer has no resize path: it compiles for one size, and
`render()` refuses another), so creating and releasing whole renderers is part of the soak.

Sampled every `--sample-every` frames: live GL objects (a census of names through glIsBuffer,
glIsTexture, glIsProgram, ... up to the highest name in use, so objects whose Python wrapper was
dropped without release() are counted too), the process's resident memory (/proc/self/statm),
GPU memory in use where the driver reports it (GL_NVX_gpu_memory_info; absent on llvmpipe), and
the median wall ms per frame over the window (the GPU finished every frame; the median leaves
out the frame that recompiles after an effect change). Each metric's slope is
a least-squares fit per 1000 frames with one offset per (view size, effect level), so a size or
effect that costs more does not read as a trend; the first `--warmup-frames` are left out.
"""
from __future__ import annotations

import ctypes
import math
import os
import time

import numpy as np

GL_GPU_MEMORY_INFO_TOTAL_AVAILABLE_MEMORY_NVX = 0x9048
GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX = 0x9049
GL_IS_FUNCTIONS = ("glIsBuffer", "glIsTexture", "glIsFramebuffer", "glIsRenderbuffer", "glIsVertexArray",
                   "glIsProgram", "glIsShader", "glIsSampler", "glIsQuery")
SIZES = [(96, 96), (80, 64), (112, 96)]
QUICK_SIZES = [(24, 24), (32, 24)]


def add_arguments(parser) -> None:
    parser.add_argument("--frames", type=int, default=None, help="frames in all (default 10000; --quick 1000)")
    parser.add_argument("--effects-every", type=int, default=50, help="frames between effect changes (default 50)")
    parser.add_argument("--resize-every", type=int, default=None,
                        help="frames between view-size changes: a new Renderer (default 500; --quick 250)")
    parser.add_argument("--sample-every", type=int, default=50, help="frames between samples (default 50)")
    parser.add_argument("--warmup-frames", type=int, default=None,
                        help="frames left out of the fits (default: 10%% of --frames, at least one cycle through "
                             "the effect levels, whose programs are compiled and cached the first time)")


class GLCensus:
    """Counts live GL objects of every kind by name: glIs*(name) for 1..(highest name + margin)."""

    def __init__(self, gl):
        from rayvr.gpu.rawgl import ProcLoader

        loader = ProcLoader()
        self.gl = gl
        self.is_fns = [loader.proc(name, ctypes.c_ubyte, [ctypes.c_uint]) for name in GL_IS_FUNCTIONS]
        self.get_integer = loader.proc("glGetIntegerv", None, [ctypes.c_uint, ctypes.POINTER(ctypes.c_int)])
        self.nvx = "GL_NVX_gpu_memory_info" in gl.extensions

    def highest_name(self) -> int:
        """The name a new buffer and texture get now: above (almost) every live name."""
        buf, tex = self.gl.buffer(reserve=4), self.gl.texture((1, 1), 4)
        top = max(buf.glo, tex.glo)
        buf.release()
        tex.release()
        return top

    def count(self) -> int:
        limit = 2 * self.highest_name() + 256
        return sum(int(bool(fn(name))) for fn in self.is_fns for name in range(1, limit))

    def gpu_memory_mb(self) -> float | None:
        if not self.nvx:
            return None
        total, free = ctypes.c_int(), ctypes.c_int()
        self.get_integer(GL_GPU_MEMORY_INFO_TOTAL_AVAILABLE_MEMORY_NVX, ctypes.byref(total))
        self.get_integer(GL_GPU_MEMORY_INFO_CURRENT_AVAILABLE_VIDMEM_NVX, ctypes.byref(free))
        return (total.value - free.value) / 1024.0


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def slope_per_1000(frames, values, groups) -> float:
    """Least-squares slope of values against frames (per 1000 frames) with one offset per group."""
    keys = sorted(set(groups))
    if len(frames) < len(keys) + 2:
        return float("nan")
    a = np.zeros((len(frames), len(keys) + 1))
    a[:, 0] = np.asarray(frames, np.float64) / 1000.0
    for row, g in enumerate(groups):
        a[row, 1 + keys.index(g)] = 1.0
    coef, *_ = np.linalg.lstsq(a, np.asarray(values, np.float64), rcond=None)
    return float(coef[0])


def _scene():
    import rayvr as rv
    from rayvr.scene import Light

    scene = rv.scenes.cornell_box()
    scene.lights.append(Light("point", position=(0.0, 0.45, 0.0), intensity=0.5, name="Soak"))
    return scene


def run(args) -> dict:
    import rayvr as rv
    from rayvr.gpu import get_context

    frames = args.frames or (1000 if args.quick else 10_000)
    resize_every = args.resize_every or (250 if args.quick else 500)
    levels = list(rv.Effect)
    warmup = args.warmup_frames if args.warmup_frames is not None else \
        max(frames // 10, args.effects_every * len(levels))
    sizes = QUICK_SIZES if args.quick else SIZES
    gpu = get_context()
    census = GLCensus(gpu.gl)
    scene = _scene()
    tall = next(i for i, inst in enumerate(scene.instances) if inst.name == "TallBox")
    base = scene.instances[tall].transform.copy()
    light = scene.lights[-1]
    samples = []   # (frame, size, effect, gl objects, rss, gpu mb, ms per frame)
    done, compiles, renderers = 0, 0, 0
    window_ms = []
    started = time.perf_counter()
    while done < frames:
        size = sizes[(done // resize_every) % len(sizes)]
        segment = min(resize_every - done % resize_every, frames - done)
        headset = rv.xr.SimulatedHeadset(preset="index", size=size, trajectory="turn", frames=segment)
        with rv.Renderer(scene, rv.graphs.hybrid(preset="raw"), sink=headset, gpu=gpu) as r:
            renderers += 1
            t0 = time.perf_counter()
            for frame in r.frames():
                n = done + frame.index
                effect = levels[(n // args.effects_every) % len(levels)]
                if n % args.effects_every == 0:
                    for m in frame.materials:
                        m.effect = effect
                moved = base.copy()
                moved[0, 3] += 0.05 * math.sin(n * 0.01)
                scene.instances[tall].transform = moved
                light.intensity = 0.5 + 0.25 * math.sin(n * 0.013)
                light.position = np.array([0.1 * math.cos(n * 0.007), 0.45, 0.1 * math.sin(n * 0.007)])
                gpu.gl.finish()
                now = time.perf_counter()
                if frame.index:
                    window_ms.append((now - t0) * 1e3)
                t0 = now
                if (n + 1) % args.sample_every == 0:
                    samples.append((n + 1, size, effect.name, census.count(), rss_mb(), census.gpu_memory_mb(),
                                    float(np.median(window_ms)) if window_ms else float("nan")))
                    window_ms = []
                    t0 = time.perf_counter()   # the census is not part of a frame
            compiles += r.compiles
            done += segment
        window_ms = []
    elapsed = time.perf_counter() - started
    kept = [s for s in samples if s[0] > warmup]
    groups = [(s[1], s[2]) for s in kept]
    rows = []
    for col, name, unit in ((3, "GL objects", "objects"), (4, "process RSS", "MB"), (5, "GPU memory", "MB"),
                            (6, "frame time", "ms")):
        values = [s[col] for s in kept]
        if not values or values[0] is None:
            rows.append([name, unit, "n/a", "n/a", "n/a", "n/a", "not reported by this driver"])
            continue
        slope = slope_per_1000([s[0] for s in kept], values, groups)
        rows.append([name, unit, round(values[0], 3), round(values[-1], 3), round(min(values), 3),
                     round(max(values), 3), round(slope, 4)])
    return {
        "columns": ["metric", "unit", "first", "last", "min", "max", "slope per 1000 frames"],
        "rows": rows,
        "notes": [f"{frames} frames in {elapsed:.0f} s; sizes {', '.join(f'{w}x{h}' for w, h in sizes)} per eye, "
                  f"changed every {resize_every} frames by a new Renderer and SimulatedHeadset ({renderers} made, "
                  f"{compiles} graph compiles); effects changed every {args.effects_every} frames; TallBox moved and "
                  f"the point light changed every frame",
                  f"{len(kept)} samples every {args.sample_every} frames after the first {warmup}; slopes fit one "
                  f"offset per (size, effect level)"],
    }
