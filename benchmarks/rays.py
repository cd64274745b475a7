"""Ray throughput of the GLSL ray-query library: primary and diffuse-bounce rays per second at
1920x1080, and their ratio to a brute-force ray-triangle roofline on the same GPU.

`--bvh-layouts bvh2,bvh4,bvh4q,bvh8` times the GPU node layouts (GpuScene bvh_layout: 64 B BVH2,
112 B BVH4, 64 B quantised BVH4, 80 B compressed BVH8) side by side.

Primary: one camera ray per pixel (trace_closest), from the scene's first camera or one framing
its bounds. Diffuse: from every primary hit, a cosine-distributed direction about the geometric
normal, origin moved by offset_ray_origin (trace_closest; incoherent rays; skipping the hit's own
instance where its triangle has the whole mesh behind it, as the path tracer does), dispatched over every
pixel (`--diffuse-layout pixels`, as a 1-spp path tracer's bounce), over the compacted queue of hit
pixels (`queue`, as a wavefront renderer holds its rays), or over that queue by persistent threads
that refill idle lanes (`persistent`, with ray_query.glsl's rq_begin/rq_step). Roofline: every ray
of a batch tested against every triangle of a small set with the same triangle test and no
BVH: the rate of ray-triangle tests the GPU sustains. `ratio` = rays/s / tests/s; a BVH that
needs ~N box and triangle tests per ray lands near 1/N. Targets (H100): >= 3 Grays/s primary,
>= 1.5 Grays/s diffuse on tauray/test.glb and the 1.04M-triangle spheres.

GPU time from timer queries where the driver has them, else finish + wall clock (llvmpipe).
"""
from __future__ import annotations

import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from ._timing import WARM_UP_S
from .bvh import resolve_scene, world_triangles

DEFAULT_SCENES = "tauray/test.glb,khronos/MetalRoughSpheresNoTextures,khronos/ToyCar,generated:2700000"
QUICK_SCENES = "cornell_box"

_HEADER = """
#include "ray_query.glsl"
#if (DIFFUSE_QUEUE || DIFFUSE_PERSISTENT) && IS_DIFFUSE
layout(local_size_x = 64) in;
#else
layout(local_size_x = 8, local_size_y = 8) in;
#endif
uniform vec3 cam_pos;
uniform vec3 cam_right;    // scaled by tan(fov/2) * aspect
uniform vec3 cam_up;       // scaled by tan(fov/2)
uniform vec3 cam_forward;
uniform ivec2 size;
uint pixel_index(ivec2 px) { return uint(px.y * size.x + px.x); }
#if RQ_STATS
layout(std430, binding = RAYVR_PASS_SSBO_2) writeonly buffer Stats { uvec4 stats[]; };
#define WRITE_STATS(i) stats[i] = uvec4(rq_stat_nodes, rq_stat_triangles, rq_stat_instances, 1u)
#else
#define WRITE_STATS(i)
#endif
vec3 camera_dir(ivec2 px) {
    vec2 ndc = (vec2(px) + 0.5) / vec2(size) * 2.0 - 1.0;
    return normalize(cam_forward + ndc.x * cam_right + ndc.y * cam_up);
}
"""

PRIMARY = _HEADER + """
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Result { float result[]; };
void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= size.x || px.y >= size.y) return;
    Hit h;
    bool hit = trace_closest(cam_pos, camera_dir(px), 1e29, h);
    result[pixel_index(px)] = hit ? h.t : -1.0;
    WRITE_STATS(pixel_index(px));
}
"""

SURFACES = _HEADER + """
layout(std430, binding = RAYVR_PASS_SSBO_1) writeonly buffer Surfaces { vec4 surfaces[]; };
void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= size.x || px.y >= size.y) return;
    vec3 d = camera_dir(px);
    Hit h;
    uint i = pixel_index(px);
    if (trace_closest(cam_pos, d, 1e29, h)) {
        SurfacePoint s = surface_at(h, d);
        surfaces[2u * i] = vec4(offset_ray_origin(s.position, s.geometric_normal), 1.0);
        surfaces[2u * i + 1u] = vec4(s.geometric_normal, uintBitsToFloat(s.exit_instance));
    } else {
        surfaces[2u * i] = vec4(0.0);
    }
}
"""

DIFFUSE = "#define IS_DIFFUSE 1\n" + _HEADER + """
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Result { float result[]; };
layout(std430, binding = RAYVR_PASS_SSBO_1) readonly buffer Surfaces { vec4 surfaces[]; };
#if DIFFUSE_QUEUE || DIFFUSE_PERSISTENT
layout(std430, binding = RAYVR_PASS_SSBO_3) readonly buffer Queue { uint queue[]; };
uniform uint queue_length;
uniform uint per_hit;
#endif
uint hash(uint x) { x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16; return x; }
// The cosine-distributed direction of sample k about normal n of pixel i.
vec3 diffuse_dir(uint i, uint k, vec3 n) {
    uint h1 = hash((i * 8u + k) * 2u + 1u), h2 = hash(h1 ^ 0x9e3779b9u);
    float u1 = float(h1 >> 8) / 16777216.0, u2 = float(h2 >> 8) / 16777216.0;
    float r = sqrt(u1), phi = 6.2831853 * u2;
    vec3 t = normalize(abs(n.x) > 0.5 ? cross(n, vec3(0, 1, 0)) : cross(n, vec3(1, 0, 0)));
    vec3 b = cross(n, t);
    return normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(0.0, 1.0 - u1)) * n);
}
#if DIFFUSE_PERSISTENT
// Persistent threads (Aila & Laine 2009): a fixed number of workgroups; a subgroup's lanes whose
// ray is done take the next rays of the queue (one atomic per subgroup) whenever fewer than
// REFILL_BELOW of its lanes are still tracing, so a warp does not idle behind its longest ray.
#ifndef REFILL_BELOW
#define REFILL_BELOW 16
#endif
#ifndef REFILL_STEPS
#define REFILL_STEPS 1
#endif
layout(std430, binding = RAYVR_PASS_SSBO_4) coherent buffer Counter { uint next_ray; };
uint lanes(bool b) { uvec2 m = unpackUint2x32(ballotARB(b)); return uint(bitCount(m.x) + bitCount(m.y)); }
void main() {
    uint total = queue_length * per_hit;
    bool tracing = false, drained = false;
    uint out_i = 0u;
    while (true) {
        if (!drained) {
            bool need = !tracing;
            uvec2 m = unpackUint2x32(ballotARB(need));
            uint n = uint(bitCount(m.x) + bitCount(m.y));
            if (n > 0u) {
                uint leader = m.x != 0u ? uint(findLSB(m.x)) : 32u + uint(findLSB(m.y));
                uint first = 0u;
                if (gl_SubGroupInvocationARB == leader) first = atomicAdd(next_ray, n);
                first = readInvocationARB(first, leader);
                uvec2 lt = unpackUint2x32(gl_SubGroupLtMaskARB);
                uint j = first + uint(bitCount(m.x & lt.x) + bitCount(m.y & lt.y));
                drained = first + n >= total;
                if (need && j < total) {
                    uint q = j % queue_length, k = j / queue_length;
                    uint i = queue[q];
                    out_i = i + k * uint(size.x * size.y);
                    vec4 p = surfaces[2u * i];
                    vec4 n = surfaces[2u * i + 1u];
                    rq_begin(p.xyz, diffuse_dir(i, k, n.xyz), 1e29, false, floatBitsToUint(n.w));
#if RQ_STATS
                    rq_stat_nodes = 0u; rq_stat_triangles = 0u; rq_stat_instances = 0u;
#endif
                    tracing = !rq_done;
                    if (rq_done) result[out_i] = -1.0;   // no instances
                }
            }
        }
        if (!anyInvocationARB(tracing)) break;
        uint steps = 0u;
        do {
            if (tracing && !rq_step()) {
                result[out_i] = rq_found ? rq_hit.t : -1.0;
                WRITE_STATS(out_i);
                tracing = false;
            }
        } while (++steps < uint(REFILL_STEPS) || lanes(tracing) >= (drained ? 1u : uint(REFILL_BELOW)));
    }
}
#else
void main() {
#if DIFFUSE_QUEUE   // 1D over the hit pixels only, in screen-tile order; y of the dispatch = sample
    if (gl_GlobalInvocationID.x >= queue_length) return;
    uint i = queue[gl_GlobalInvocationID.x];
    uint k = gl_GlobalInvocationID.y;
#else               // 2D over every pixel; z of the dispatch = sample
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= size.x || px.y >= size.y) return;
    uint i = pixel_index(px);
    uint k = gl_GlobalInvocationID.z;
#endif
    uint out_i = i + k * uint(size.x * size.y);
    vec4 p = surfaces[2u * i];
    if (p.w == 0.0) { result[out_i] = -2.0; WRITE_STATS(out_i); return; }
    Hit h;
    vec4 n = surfaces[2u * i + 1u];
    bool hit = trace_closest(p.xyz, diffuse_dir(i, k, n.xyz), 1e29, floatBitsToUint(n.w), h);
    result[out_i] = hit ? h.t : -1.0;
    WRITE_STATS(out_i);
}
#endif
"""

ROOFLINE = """
#include "ray_query.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) writeonly buffer Result { float result[]; };
layout(std430, binding = RAYVR_PASS_SSBO_1) readonly buffer Tris { vec4 tris[]; };
uniform uint tri_count;
uniform uint ray_count;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= ray_count) return;
    float a = float(i) * 0.618034;
    vec3 o = vec3(fract(a) * 2.0 - 1.0, fract(a * 7.31) * 2.0 - 1.0, 5.0);
    RqRay r = rq_make_ray(o, normalize(vec3(0.1 * fract(a * 3.7), 0.1 * fract(a * 1.3), -1.0)));
    float best = 1e29;
    for (uint k = 0u; k < tri_count; ++k) {
        float t;
        vec2 bary;
        if (rq_triangle(r, tris[3u * k].xyz, tris[3u * k + 1u].xyz, tris[3u * k + 2u].xyz, best, t, bary)) best = t;
    }
    result[i] = best;
}
"""


def add_arguments(parser) -> None:
    parser.add_argument("--scenes", default=None,
                        help=f"comma-separated scenes (default {DEFAULT_SCENES}; quick: {QUICK_SCENES})")
    parser.add_argument("--size", default="1920x1080", help="WIDTHxHEIGHT (quick: 96x54)")
    parser.add_argument("--iterations", type=int, default=10, help="timed dispatches per kind (quick: 1)")
    parser.add_argument("--roofline-rays", type=int, default=1 << 20, help="rays in the roofline kernel (quick: 4096)")
    parser.add_argument("--roofline-tris", type=int, default=1024, help="triangles per ray in the roofline (quick: 64)")
    parser.add_argument("--variants", default="",
                        help="ray_query.glsl #define sets to compare, 'NAME:KEY=V;KEY=V|NAME2:...' "
                             "(default: one row per scene with the library's defaults)")
    parser.add_argument("--rounds", type=int, default=3,
                        help="interleaved timing rounds over the variants; the fastest round counts "
                             "(a shared GPU's timings vary between dispatches; quick: 1)")
    parser.add_argument("--diffuse-per-hit", type=int, default=1,
                        help="diffuse rays from each primary hit (1..8; 1: one bounce of a 1-spp path tracer)")
    parser.add_argument("--diffuse-layout", default="pixels", choices=("pixels", "queue", "persistent"),
                        help="pixels: a 2D dispatch over every pixel, misses leave at once; queue: a 1D "
                             "dispatch over the hit pixels only, in 8x4 screen-tile order; persistent: the "
                             "same queue taken by a fixed set of workgroups whose lanes refill as their rays "
                             "finish (variant defines PERSISTENT_GROUPS, REFILL_BELOW, REFILL_STEPS)")
    parser.add_argument("--stats", action="store_true",
                        help="also count node visits, triangle tests and instance entries per ray (RQ_STATS)")
    parser.add_argument("--bvh-layouts", default="",
                        help="comma-separated BVH node layouts to compare (bvh2: 64 B BVH2, bvh4: 112 B BVH4, "
                             "bvh4q: 64 B quantised BVH4, bvh8: 80 B compressed 8-wide), one GpuScene and one row "
                             "per layout and variant, "
                             "timed in the same interleaved rounds (default: GpuScene's default layout)")


def _camera(scene, aspect: float):
    if scene.cameras:
        cam = scene.cameras[0]
        m = cam.transform
        right, up, back = (m[:3, k] / np.linalg.norm(m[:3, k]) for k in range(3))
        pos, yfov = m[:3, 3], cam.yfov
    else:   # look at the bounds' largest face, from just far enough that it fills the view
        lo, hi = scene.bounds()
        centre, ext = (lo + hi) / 2, hi - lo
        eye3 = np.eye(3)
        k = int(np.argmin(ext))
        right, up = {0: (-eye3[2], eye3[1]), 1: (eye3[0], -eye3[2]), 2: (eye3[0], eye3[1])}[k]
        back = eye3[k]
        yfov = math.radians(45)
        dist = max(abs(ext @ right) / aspect, abs(ext @ up)) / 2 / math.tan(yfov / 2) + ext[k] / 2
        pos = centre + back * dist
    th = math.tan(yfov / 2)
    return pos, right * th * aspect, up * th, -back


def _time(gl, use_queries: bool, fn, iterations: int) -> float:
    """Median milliseconds of fn() over iterations (after one warm-up run)."""
    fn()
    gl.finish()
    times = []
    for _ in range(iterations):
        if use_queries:
            q = gl.query(time=True)
            with q:
                fn()
            times.append(q.elapsed / 1e6)
        else:
            gl.finish()
            t0 = time.perf_counter()
            fn()
            gl.finish()
            times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


PERSISTENT_GROUPS = 2048   # workgroups of 64 of the persistent layout (variant define PERSISTENT_GROUPS)
SUBGROUP_EXTENSIONS = ("#extension GL_ARB_shader_ballot : require\n#extension GL_ARB_shader_group_vote : require\n"
                       "#extension GL_ARB_gpu_shader_int64 : require\n")


def _program(gl, folder: Path, name: str, text: str, defines: dict, header: str = ""):
    from rayvr.gpu import compute_program

    path = folder / f"{name}.comp"
    path.write_text(text)
    return compute_program(gl, path, defines, header=header)


def _roofline(gl, caps, folder: Path, rays: int, tris: int, iterations: int) -> float:
    from rayvr.gpu.bindings import BINDINGS
    from rayvr.scene import builtin, GpuScene
    from rayvr.gpu import get_context

    gs = GpuScene(get_context(), builtin.quad())   # only for the defines and bindings
    prog = _program(gl, folder, "roofline", ROOFLINE, gs.defines())
    rng = np.random.default_rng(0)
    centre = rng.uniform(-1, 1, size=(tris, 1, 3))
    tri = np.zeros((tris, 3, 4), np.float32)
    tri[:, :, :3] = centre + rng.normal(0, 0.05, size=(tris, 3, 3))
    tri[:, :, 2] = rng.uniform(-1, 1, size=(tris, 1))
    tb, out = gl.buffer(tri.tobytes()), gl.buffer(reserve=rays * 4)
    tb.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
    out.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    prog["tri_count"] = tris
    prog["ray_count"] = rays
    ms = _time(gl, caps.timer_queries, lambda: prog.run((rays + 63) // 64), iterations)
    tb.release(), out.release(), gs.release()
    return rays * tris / (ms / 1e3)


def _scene(spec: str):
    """resolve_scene, or with 'flat:' (or 'flat-sah:') every instance's triangles in world space
    as one mesh and one instance: the one-level BVH a static scene could use."""
    kind, _, rest = spec.partition(":")
    if kind not in ("flat", "flat-sah"):
        return resolve_scene(spec), "auto"
    from rayvr.scene import Material, Scene

    src = resolve_scene(rest)
    tris = world_triangles(src)
    s = Scene(f"flat {src.name}")
    s.add_material(Material("Flat"))
    s.add_object("Flat", tris.reshape(-1, 3), np.arange(3 * len(tris), dtype=np.uint32), 0)
    s.cameras = list(src.cameras)
    return s, "sah" if kind == "flat-sah" else "auto"


def _tile_queue(gl, hit: np.ndarray, w: int):
    """(buffer, length): the indices of the pixels with a primary hit (`hit`, row-major), ordered by
    8x4 screen tile (a warp's worth of neighbouring pixels), as a wavefront renderer's compacted ray
    queue holds them."""
    idx = np.flatnonzero(hit).astype(np.uint32)
    x, y = idx % w, idx // w
    order = np.lexsort((x % 8, y % 4, x // 8, y // 4))
    q = idx[order]
    return gl.buffer(q.tobytes() if len(q) else b"\0\0\0\0"), int(len(q))


def parse_variants(text: str) -> list[tuple[str, dict]]:
    """'NAME:KEY=V;KEY=V|NAME2' -> [(name, {KEY: V})]; empty text: one default variant."""
    out = []
    for part in filter(None, (p.strip() for p in text.split("|"))):
        name, _, defs = part.partition(":")
        out.append((name, {k.strip(): int(v) for k, v in (d.split("=") for d in defs.split(";") if d.strip())}))
    return out or [("default", {})]


def _stats(gl, progs: dict, dispatch: dict, stats_buf, hits_mask, pixels: int) -> dict:
    """Mean node visits, triangle tests and instance entries per ray of the RQ_STATS kernels."""
    out = {}
    for kind in ("primary", "diffuse"):
        dispatch[kind](progs[kind])
        gl.finish()
        st = np.frombuffer(stats_buf.read(), np.uint32).reshape(-1, 4).astype(np.float64)
        rays = st[:pixels] if kind == "primary" else st[hits_mask]
        for k, col in enumerate(("nodes", "tris", "instances")):
            out[f"{kind}_{col}"] = float(rays[:, k].mean()) if len(rays) else 0.0
    return out


def run(args) -> dict:
    from rayvr.cli.options import parse_size
    from rayvr.gpu import get_context
    from rayvr.gpu.bindings import BINDINGS
    from rayvr.scene import GpuScene

    gpu = get_context()
    gl, caps = gpu.gl, gpu.caps
    specs = (args.scenes or (QUICK_SCENES if args.quick else DEFAULT_SCENES)).split(",")
    w, h = (96, 54) if args.quick and args.size == "1920x1080" else parse_size(args.size)
    iters = 1 if args.quick else args.iterations
    rounds = 1 if args.quick else max(1, args.rounds)
    variants = parse_variants(args.variants)
    layouts = [x.strip() for x in args.bvh_layouts.split(",") if x.strip()] or [None]
    folder = Path(tempfile.mkdtemp(prefix="rayvr-rays-"))
    roof = _roofline(gl, caps, folder, 4096 if args.quick else args.roofline_rays,
                     64 if args.quick else args.roofline_tris, iters)
    rows = []
    for spec in specs:
        scene, method = _scene(spec.strip())
        scenes, build_s = {}, {}   # per BVH layout
        for layout in layouts:
            t0 = time.perf_counter()
            scenes[layout] = GpuScene(gpu, scene, bvh_method=method, progress=False,
                                      **({} if layout is None else {"bvh_layout": layout}))
            build_s[layout] = time.perf_counter() - t0
        gs = scenes[layouts[0]]
        pos, right, up, fwd = _camera(scene, w / h)
        per_hit = max(1, min(8, args.diffuse_per_hit))
        queue_layout = args.diffuse_layout in ("queue", "persistent")
        persistent = args.diffuse_layout == "persistent"
        counter = gl.buffer(reserve=4) if persistent else None
        result = gl.buffer(reserve=w * h * 4 * per_hit)
        surfaces = gl.buffer(reserve=w * h * 32)
        stats_buf = gl.buffer(reserve=w * h * 16 * per_hit) if args.stats else None
        groups = ((w + 7) // 8, (h + 7) // 8)
        queue = None   # hit pixels in 8x4-tile order (queue layout), made once from the surfaces

        def run_diffuse(prog, groups_persistent=PERSISTENT_GROUPS):
            if persistent:
                counter.clear()
                prog["queue_length"] = queue[1]
                prog["per_hit"] = per_hit
                prog.run(groups_persistent)
            elif queue_layout:
                prog["queue_length"] = queue[1]
                prog.run((queue[1] + 63) // 64, per_hit)
            else:
                prog.run(*groups, per_hit)

        dispatch = {"primary": lambda p: p.run(*groups), "diffuse": run_diffuse}

        def programs(defines):
            defines = {**defines, "DIFFUSE_QUEUE": int(queue_layout and not persistent),
                       "DIFFUSE_PERSISTENT": int(persistent)}
            progs = {k: _program(gl, folder, k, src, defines, SUBGROUP_EXTENSIONS if persistent and k == "diffuse" else "")
                     for k, src in
                     (("primary", PRIMARY), ("surfaces", SURFACES), ("diffuse", DIFFUSE))}
            for p in progs.values():
                for name, v in (("cam_pos", pos - gs.origin), ("cam_right", right), ("cam_up", up), ("cam_forward", fwd)):
                    if name in p:
                        p[name] = tuple(float(x) for x in v)
                p["size"] = (w, h)
            progs["groups"] = defines.get("PERSISTENT_GROUPS", PERSISTENT_GROUPS)
            return progs

        result.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
        surfaces.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_1"])
        if stats_buf is not None:
            stats_buf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_2"])
        if counter is not None:
            counter.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_4"])
        counts: dict[tuple, dict] = {}
        compiled = [((layout, vname), vdefs, programs({**scenes[layout].defines(), **vdefs}))
                    for layout in layouts for vname, vdefs in variants]
        best: dict[tuple, dict] = {}
        warm_until = time.perf_counter() + (0.0 if args.quick else WARM_UP_S)
        gs.bind()
        while time.perf_counter() < warm_until:   # let the GPU clock up before timing
            compiled[0][2]["primary"].run(*groups)
            gl.finish()
        for _ in range(rounds):   # interleaved rounds; the fastest counts
            for key, vdefs, progs in compiled:
                scenes[key[0]].bind()
                primary_ms = _time(gl, caps.timer_queries, lambda: progs["primary"].run(*groups), iters)
                primary_hit = np.frombuffer(result.read(w * h * 4), np.float32) > 0   # = the surfaces' hits
                hits = int(primary_hit.sum())
                progs["surfaces"].run(*groups)
                gl.memory_barrier()
                if queue_layout and queue is None:
                    queue = _tile_queue(gl, primary_hit, w)
                    queue[0].bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_3"])
                diffuse_ms = _time(gl, caps.timer_queries, lambda: run_diffuse(progs["diffuse"], progs["groups"]), iters)
                d = np.frombuffer(result.read(), np.float32)
                if queue_layout:   # pixels off the queue were never written: mark them as no-ray
                    d = np.where(np.tile(primary_hit, per_hit), d, -2.0)
                if stats_buf is not None and key not in counts:
                    counts[key] = _stats(gl, programs({**scenes[key[0]].defines(), **vdefs, "RQ_STATS": 1}),
                                         dispatch, stats_buf, d > -1.5, w * h)
                b = best.setdefault(key, {"primary_ms": primary_ms, "diffuse_ms": diffuse_ms})
                b["primary_ms"], b["diffuse_ms"] = min(b["primary_ms"], primary_ms), min(b["diffuse_ms"], diffuse_ms)
                b["hits"], b["bounce_hits"] = hits, int((d > 0).sum())
        for key, _, _ in compiled:
            layout, vname = key
            rep = scenes[layout].report()
            b = best[key]
            primary_ms, diffuse_ms, hits, bounce_hits = b["primary_ms"], b["diffuse_ms"], b["hits"], b["bounce_hits"]
            primary_rate = w * h / (primary_ms / 1e3)
            diffuse_rate = hits * per_hit / (diffuse_ms / 1e3) if hits else 0.0
            rows.append({
                "scene": spec, "variant": vname, "bvh_layout": rep["bvh_layout"], "triangles": gs.triangle_count,
                "size": f"{w}x{h}",
                "primary_ms": primary_ms, "primary_Grays_s": primary_rate / 1e9,
                "diffuse_ms": diffuse_ms, "diffuse_Grays_s": diffuse_rate / 1e9,
                "diffuse_per_hit": per_hit, "diffuse_layout": args.diffuse_layout,
                "primary_hit_frac": hits / (w * h), "diffuse_hit_frac": bounce_hits / max(hits * per_hit, 1),
                "roofline_Gtests_s": roof / 1e9, "primary_ratio": primary_rate / roof, "diffuse_ratio": diffuse_rate / roof,
                "gpu_bytes_per_tri": rep["geometry_bytes_per_triangle"],
                "blas_node_bytes_per_tri": rep["blas_node_bytes_per_triangle"], "scene_build_s": build_s[layout],
                **counts.get(key, {}),
            })
        result.release(), surfaces.release()
        for g in scenes.values():
            g.release()
        if queue is not None:
            queue[0].release()
        if stats_buf is not None:
            stats_buf.release()
        if counter is not None:
            counter.release()
    cols = ["scene", "variant", "bvh_layout", "triangles", "size", "primary_ms", "primary_Grays_s", "diffuse_per_hit",
            "diffuse_layout", "diffuse_ms", "diffuse_Grays_s",
            "primary_hit_frac", "diffuse_hit_frac", "roofline_Gtests_s", "primary_ratio", "diffuse_ratio",
            "gpu_bytes_per_tri", "blas_node_bytes_per_tri", "scene_build_s"]
    if args.stats:
        cols += [f"{k}_{c}" for k in ("primary", "diffuse") for c in ("nodes", "tris", "instances")]
    notes = [f"timing: {'GPU timer queries' if caps.timer_queries else 'finish + wall clock'}, median of {iters}, "
             f"best of {rounds} interleaved rounds",
             "diffuse rays are cast from primary hits only; rays/s counts those rays",
             "roofline: brute-force ray-triangle tests/s (same test as the traversal, no BVH)"]
    if args.stats:
        notes.append("stats: mean internal nodes visited (BVH2, BVH4 or BVH8 nodes, by bvh_layout) / triangle tests / "
                     "BLAS entries per ray")
    return {"columns": cols, "rows": rows, "notes": notes}
