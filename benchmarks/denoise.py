"""Denoisers: SVGF's GPU ms and memory, and the error of 1 spp + SVGF against raw path tracing.

Two parts, one table (the `part` column):
- `time`: path_traced(denoise="svgf") (one bounce: the filter's cost does not depend on the
  light) at each --time-sizes entry (default stereo 2 x 1440x1600 and a 64-view light field of
  512x683); the SVGF and TAA passes' mean GPU ms from the graph profile (timer queries on
  NVIDIA, finish+wall on llvmpipe), the bytes the compile report gives SVGF's resources, and
  OIDN's wall ms for the same views (pyoidn's CPU device on this machine's numpy images, one
  view timed and multiplied by the view count: it is not in the GPU path at all).
- `error`: rayvr.tune's error study (a converged, checked reference; FLIP at the preset's pixels
  per degree, PSNR, relMSE; static and along a head trajectory) of PATH_TRACED at 1, 4 and 16 spp
  raw, 1 spp + SVGF, and 1 and 4 spp + OIDN, on each --scenes entry (default tauray/test.glb and
  the Cornell box), stereo. The static rows are judged after the study's warm-up and timed
  frames (SVGF's history is that long); the trajectory rows from the first frame of the path.
`--kernels`: the SVGF settings both parts run, one row each: the a-trous kernel width (3 or 5;
the SVGF pass's `kernel`), optionally with its iteration count after a colon (e.g. 3,5,3:6: the
3x3 kernel, the 5x5, the 3x3 with 6 iterations; the rows say 'SVGF 3x3', 'SVGF 5x5',
'SVGF 3x3 x6'). Without it, one row at the pass's defaults ('SVGF').
`--quick`: small sizes for llvmpipe (time: 2 x 64x64 and 8 x 32x43; error: 2 x 32x32, a 32 x 8 spp
reference, no bias floors). The H200 targets (SVGF <= 1.5 ms at 2 x 1440x1600; 1 spp + SVGF under
raw 16 spp's error at < 1/10 of its GPU time) are judged from a full run on that GPU only.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ._study import add_figure_options, resolve_figures, stat_cell

DEFAULT_SCENES = [str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb"), "cornell_box"]
TIME_SIZES = ("2x1440x1600", "64x512x683")
QUICK_TIME_SIZES = ("2x64x64", "8x32x43")
# option: (full run, --quick)
FIGURES = {"size": ("1440x1600", "32x32"), "timing_frames": (50, 4), "warmup": (10, 2), "reference_frames": (256, 32),
           "reference_spp": (16, 8), "motion_frames": (32, 8), "motion_samples": (3, 2), "frames": (4, 2)}
COLUMNS = ["part", "scene", "config", "views x size", "GPU ms", "SVGF ms", "TAA ms", "SVGF MB", "OIDN wall ms",
           "OIDN CUDA ms fast / balanced / high", "FLIP", "PSNR dB", "relMSE", "FLIP in motion", "PSNR in motion"]


def add_arguments(parser) -> None:
    parser.add_argument("--scenes", help="glTF paths or built-in names, comma-separated (default: tauray/test.glb "
                                         "and cornell_box)")
    parser.add_argument("--time-sizes", help="VIEWSxWIDTHxHEIGHT entries for the timing part, comma-separated "
                                             f"(default {','.join(TIME_SIZES)}; quick {','.join(QUICK_TIME_SIZES)})")
    parser.add_argument("--parts", default="time,error", help="time, error or both (default)")
    parser.add_argument("--kernels", help="SVGF a-trous kernels to run, one row each, comma-separated: 3 or 5, "
                                          "optionally :ITERATIONS (e.g. 3,5,3:6); default: the pass's defaults")
    parser.add_argument("--preset", default="index", help="headset whose pixels per degree FLIP uses")
    parser.add_argument("--views", type=int, default=2, help="views of the error part (default 2)")
    add_figure_options(parser, FIGURES)
    parser.add_argument("--cache", help="reference cache folder (default ~/.cache/rayvr/references)")


def _entry(text: str) -> tuple[int, tuple[int, int]]:
    from rayvr.cli.options import parse_size
    from rayvr.errors import OptionError

    views, _, size = text.partition("x")
    if not views.isdigit() or not size:
        raise OptionError(f"--time-sizes {text}: give VIEWSxWIDTHxHEIGHT, e.g. 2x1440x1600")
    return int(views), parse_size(size)


def _kernel(text: str) -> tuple[int, int | None]:
    """--kernels entry 'K' or 'K:ITERATIONS': (kernel, iterations or None for the pass's default)."""
    from rayvr.errors import OptionError
    from rayvr.passes.svgf.svgf import KERNELS, MAX_ITERATIONS

    kernel, colon, iterations = str(text).partition(":")
    ok = kernel.isdigit() and int(kernel) in KERNELS and (
        not colon or iterations.isdigit() and 0 <= int(iterations) <= MAX_ITERATIONS)
    if not ok:
        raise OptionError(f"--kernels {text}: give 3 or 5 (the a-trous kernel width), optionally :ITERATIONS "
                          f"from 0 to {MAX_ITERATIONS}, e.g. 3,5 or 3:6")
    return int(kernel), int(iterations) if iterations else None


DEFAULT_KERNELS = ((None, None),)   # no --kernels: the SVGF pass's defaults


def svgf_props(kernel: int | None, iterations: int | None) -> dict:
    """The SVGF pass properties of one --kernels entry (None: the pass's default)."""
    return {**({} if kernel is None else {"kernel": kernel}),
            **({} if iterations is None else {"iterations": iterations})}


def svgf_label(kernel: int | None, iterations: int | None) -> str:
    """'SVGF' with its kernel (and iterations when given): 'SVGF 3x3', 'SVGF 3x3 x6'; 'SVGF' at
    the pass's defaults."""
    return ("SVGF" + ("" if kernel is None else f" {kernel}x{kernel}")
            + ("" if iterations is None else f" x{iterations}"))


def time_rows(scene_spec: str, entries, frames: int, warmup: int, kernels=DEFAULT_KERNELS) -> list[list]:
    import rayvr as rv
    from rayvr.cli.options import load_scene_arg
    from rayvr.xr.cameras import default_views

    from ._timing import wall_ms_per_frame

    scene = load_scene_arg(scene_spec)
    rows = []
    for views, size in entries:
        oidn, oidn_cuda = _oidn_ms(size, views), _oidn_cuda_ms(size, views)
        for kernel, iterations in kernels:
            graph = rv.graphs.path_traced(max_bounces=1, denoise="svgf")
            if svgf_props(kernel, iterations):
                graph.update_pass("SVGF", svgf_props(kernel, iterations))
            with rv.Renderer(scene, graph, views=default_views(scene, views, size)) as r:
                wall_ms_per_frame(r, frames, warmup)
                prof = r.profile()
                svgf_bytes = sum(res.bytes for name, res in r.compiled.plan.resources.items()
                                 if name.startswith("SVGF."))
                svgf, taa = prof.passes["SVGF"].mean_ms, prof.passes["TAA"].mean_ms
                total = sum(p.mean_ms for p in prof.passes.values())
            rows.append(["time", scene.name, f"1 spp + {svgf_label(kernel, iterations)} + TAA (1 bounce)",
                         f"{views}x{size[0]}x{size[1]}", round(total, 3), round(svgf, 3), round(taa, 3),
                         float(f"{svgf_bytes / 2 ** 20:.3g}"), oidn, oidn_cuda, "-", "-", "-", "-", "-"])
    return rows


def _oidn_ms(size, views: int):
    """Wall ms of OIDN (pyoidn's CPU device, quality 'high', albedo and normal) on `views` images
    of `size`: one timed after a warm-up call, times `views`."""
    try:
        import pyoidn
    except ImportError:
        return "no pyoidn"
    rng = np.random.default_rng(0)
    w, h = size
    color = rng.gamma(1.0, 0.5, (h, w, 3)).astype(np.float32)
    albedo = np.full((h, w, 3), 0.6, np.float32)
    normal = np.zeros((h, w, 3), np.float32)
    normal[..., 2] = 1.0
    pyoidn.denoise(color, albedo, normal, hdr=True, clean_aux=True)
    t0 = time.perf_counter()
    pyoidn.denoise(color, albedo, normal, hdr=True, clean_aux=True)
    return round((time.perf_counter() - t0) * 1e3 * views, 1)


def _oidn_cuda_ms(size, views: int, repeats: int = 10) -> str:
    """OIDN on pyoidn's CUDA device (torch CUDA tensors, RT filter, HDR, albedo and normal, clean
    aux) for `views` images of `size` at qualities fast / balanced / high: the mean of `repeats`
    calls after two warm-ups, synchronised, times `views`; or why it could not run."""
    try:
        import pyoidn
        import torch
    except ImportError as exc:
        return f"no {exc.name}"
    if not torch.cuda.is_available():
        return "no CUDA"
    w, h = size
    g = torch.Generator(device="cuda").manual_seed(0)
    color = torch.rand((h, w, 3), device="cuda", generator=g) * 2.0
    albedo = torch.full((h, w, 3), 0.6, device="cuda")
    normal = torch.zeros((h, w, 3), device="cuda")
    normal[..., 2] = 1.0
    out = []
    for quality in ("fast", "balanced", "high"):
        for _ in range(2):
            pyoidn.denoise(color, albedo, normal, hdr=True, clean_aux=True, quality=quality)
        torch.cuda.synchronize()
        t0 = time.perf_counter()
        for _ in range(repeats):
            pyoidn.denoise(color, albedo, normal, hdr=True, clean_aux=True, quality=quality)
        torch.cuda.synchronize()
        out.append(f"{(time.perf_counter() - t0) * 1e3 / repeats * views:.2f}")
    return " / ".join(out)


def _svgf_builder(kernel: int, iterations: int | None):
    """The study's hybrid graph builder with SVGF's kernel (and iterations) set."""
    from rayvr.study.configs import hybrid_graph

    def build(**options):
        g = hybrid_graph(**options)
        g.update_pass("SVGF", svgf_props(kernel, iterations))
        return g

    build.__name__ = f"hybrid_{svgf_label(kernel, iterations).lower().replace(' ', '_')}"
    return build


def error_configs(oidn: bool, kernels=DEFAULT_KERNELS):
    from rayvr import Effect
    from rayvr.study import Config

    configs = [Config(f"PATH_TRACED {n} spp", Effect.PATH_TRACED, options={"spp": n}) for n in (1, 4, 16)]
    configs += [Config(f"PATH_TRACED 1 spp + {svgf_label(k, i)}", Effect.PATH_TRACED,
                       graph=_svgf_builder(k, i) if svgf_props(k, i) else None, options={"spp": 1, "denoise": "svgf"})
                for k, i in kernels]
    if oidn:
        configs += [Config(f"PATH_TRACED {n} spp + OIDN", Effect.PATH_TRACED, options={"spp": n, "denoise": "oidn"})
                    for n in (1, 4)]
    return configs


def error_rows(scene_spec: str, args, f: dict, quick: bool, kernels=DEFAULT_KERNELS) -> tuple[list[list], list[str]]:
    from rayvr.cli.options import load_scene_arg, parse_size
    from rayvr.study import Motion, ReferenceSettings, StudySettings, cached_reference, make_views, measure
    from rayvr.study.configs import available_denoisers
    from rayvr.study.timing import GPU_WARM_UP_S
    from rayvr.xr.presets import get_preset

    scene = load_scene_arg(scene_spec)
    size = parse_size(f["size"])
    view_set = make_views(scene, args.views, size)
    ref_settings = ReferenceSettings(f["reference_frames"], f["reference_spp"])
    motion = Motion("turn", f["motion_frames"], f["motion_samples"], get_preset(args.preset).default_refresh)
    settings = StudySettings(frames=f["frames"], timing_frames=f["timing_frames"], warmup=f["warmup"],
                             warmup_s=0.0 if quick else GPU_WARM_UP_S, motion=motion, floors=not quick,
                             progressive_frames=0, preset=args.preset)
    ref = cached_reference(scene, view_set, ref_settings, args.cache)
    configs = error_configs("oidn" in available_denoisers(), kernels)
    for c in configs:   # the reference's bounces, as the study's standard set uses
        c.options.setdefault("path_bounces", ref_settings.max_bounces)
    results = measure(scene, configs, views=view_set, size=size, reference=ref, settings=settings,
                      cache_dir=args.cache, progress=True)
    rows = []
    for r in results.rows:
        motion_stats = r.motion or {}
        rows.append(["error", scene.name, r.name, f"{len(view_set)}x{size[0]}x{size[1]}", round(r.gpu_ms, 3),
                     _ms(r.pass_ms.get("SVGF")), _ms(r.pass_ms.get("TAA")), "-", _ms(r.pass_ms.get("Denoise")), "-",
                     stat_cell(r.errors.get("flip")), stat_cell(r.errors.get("psnr")), stat_cell(r.errors.get("relmse")),
                     stat_cell(motion_stats.get("flip")), stat_cell(motion_stats.get("psnr"))])
    notes = [f"{scene.name}: reference {ref.verdict()}"]
    return rows, notes


def _ms(value):
    return "-" if value is None else round(value, 3)


def run(args) -> dict:
    from rayvr.cli.converge import parse_list

    quick = args.quick
    f = resolve_figures(args, FIGURES)
    parts = set(parse_list(args.parts, "--parts", str))
    scenes = parse_list(args.scenes, "--scenes", str) if args.scenes else DEFAULT_SCENES
    kernels = ([_kernel(e) for e in parse_list(args.kernels, "--kernels", str)] if args.kernels
               else DEFAULT_KERNELS)
    entries = [_entry(e) for e in parse_list(args.time_sizes, "--time-sizes", str)] if args.time_sizes else \
        [_entry(e) for e in (QUICK_TIME_SIZES if quick else TIME_SIZES)]
    rows, notes = [], []
    if "time" in parts:
        for spec in scenes:
            rows += time_rows(spec, entries, f["timing_frames"], f["warmup"], kernels)
    if "error" in parts:
        for spec in scenes:
            more, more_notes = error_rows(spec, args, f, quick, kernels)
            rows += more
            notes += more_notes
    notes += ["time: SVGF ms and TAA ms are the passes' mean GPU time per frame (all views in one dispatch); "
              "SVGF MB: its resources in the compile report (history, moments, surfaces, the filter's scratch, "
              "its output); OIDN wall ms: pyoidn's CPU device, outside the GPU timers; OIDN CUDA ms: pyoidn's CUDA "
              "device on torch CUDA tensors (where the machine has them), wall time of synchronised calls",
              "error: mean ± std over judged frames x views; FLIP at the preset's pixels per degree; in motion: "
              "the 'turn' trajectory, judged frames along it, each against its own reference",
              "targets (H200): SVGF <= 1.5 ms at 2x1440x1600; 1 spp + SVGF below raw 16 spp's error at < 1/10 of "
              "its GPU time; a run on llvmpipe (--quick) does not measure them"]
    return {"columns": COLUMNS, "rows": rows, "notes": notes}
