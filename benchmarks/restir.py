"""ReSTIR DI against the light table's sampling: GPU ms and error of the hybrid graph's direct light,
RTShadows (`light_samples` 1, 2, 4, ...) against ReSTIRDI (`direct="restir"`), every material SHADOWS.

Two parts (`--parts`), one table:
- `many`: the scene (`--scene`) with `--lights` point lights (default 10,000: random in its bounds,
  intensities over two decades, random colours) and `--emitters` small emissive boxes added. The
  target: ReSTIR's relMSE <= 0.25x RTShadows' at equal Shadows-pass GPU ms (RTShadows' relMSE
  interpolated log-log between its light_samples rows at ReSTIR's ms; `equal ms` rows).
- `scene`: the scene as it is. The target (tauray/test.glb): SHADOWS with ReSTIR <= 0.5x the FLIP
  of plain SHADOWS (RTShadows, 1 light sample) at <= 1.3x its frame GPU ms.
Errors are against a converged reference of the same direct light: RTShadows with
`--reference-samples` light samples over `--reference-frames` frames, in two independent halves
whose difference gives the reference's own relMSE (noted; it adds to every row's, so the
equal-ms ratio compares the rows' relMSE less the reference's). Each configuration is judged on
`--error-frames` single frames after `--warmup` frames (ReSTIR's history fills), still views:
relMSE of the linear radiance (Composite.color) without its largest 0.1% (`relMSE`: the few pixels
beside a light that a random placement puts next to a wall are noisy in every image, the
reference's too) and of every pixel, and FLIP of the displayed images (ACES at the reference's
exposure, the `--preset` headset's pixels per degree). GPU ms are the graph profile's
means over `--frames` timed frames (timer queries on a GPU; finish and wall time on llvmpipe,
where the times mean little).
`--quick`: 2 x 32x32, few frames, 200 lights: a smoke run for llvmpipe.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._restir_sets import RESTIR_SETS

DEFAULT_SCENE = str(Path(__file__).resolve().parents[2] / "shared" / "scenes" / "tauray" / "test.glb")
TARGET_RELMSE_RATIO = 0.25   # many: ReSTIR / RTShadows relMSE at equal Shadows ms
TARGET_FLIP_RATIO = 0.5      # scene: ReSTIR / plain SHADOWS FLIP
TARGET_MS_RATIO = 1.3        # scene: ReSTIR / plain SHADOWS frame ms
# option: (full run, --quick)
FIGURES = {"size": ("1440x1600", "32x32"), "frames": (50, 3), "warmup": (32, 8), "error_frames": (4, 2),
           "reference_frames": (256, 16), "reference_samples": (64, 8), "lights": (10000, 200), "emitters": (64, 8)}
COLUMNS = ["part", "scene", "config", "views x size", "Shadows ms", "frame ms", "relMSE", "relMSE (all px)", "FLIP",
           "note"]


def add_arguments(parser) -> None:
    parser.add_argument("--scene", default=DEFAULT_SCENE, help="glTF path or built-in scene name (default "
                                                               "tauray/test.glb)")
    parser.add_argument("--parts", default="many,scene", help="many, scene or both (default)")
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--light-samples", default="1,2,4,8,16",
                        help="RTShadows' light_samples rows, comma-separated (default 1,2,4,8,16)")
    parser.add_argument("--restir", default="defaults",
                        help="ReSTIRDI property sets, a row each: names from benchmarks/_restir_sets.py "
                             f"(comma-separated: {', '.join(RESTIR_SETS)}), or a JSON object of properties or a "
                             "list of them (default: the pass's own)")
    parser.add_argument("--preset", default="index", help="headset whose pixels per degree FLIP uses")
    parser.add_argument("--seed", type=int, default=1, help="the added lights' random seed")
    for name, (full, quick) in FIGURES.items():
        parser.add_argument(f"--{name.replace('_', '-')}", default=None,
                            help=f"default {full} (quick {quick})")


def _figure(args, name):
    value = getattr(args, name)
    if value is None:
        value = FIGURES[name][1 if args.quick else 0]
    return value if name == "size" else int(value)


def add_many_lights(scene, lights: int, emitters: int, seed: int) -> None:
    """`lights` point lights and `emitters` emissive boxes at random in the scene's bounds (shrunk
    by a tenth), every material SHADOWS."""
    import rayvr as rv
    from rayvr.scene import builtin
    from rayvr.scene.model import Light

    lo, hi = scene.bounds()
    pad = 0.1 * (hi - lo)
    lo, hi = lo + pad, hi - pad
    extent = float(np.linalg.norm(hi - lo))
    rng = np.random.default_rng(seed)
    power = 4.0 * extent * extent / max(lights, 1)   # cd: the lights together light the scene as a lamp of 4 ext^2
    for i in range(lights):
        scene.lights.append(Light("point", position=rng.uniform(lo, hi), intensity=float(power * 10 ** rng.uniform(-1, 1)),
                                  color=tuple(rng.uniform(0.3, 1.0, 3)), name=f"bench_light_{i}"))
    half = extent / 200
    for i in range(emitters):
        c = rng.uniform(lo, hi)
        name = f"bench_emitter_{i}"
        scene.add_material(builtin.lambert(name, (0.5, 0.5, 0.5), emissive=tuple(rng.uniform(0.3, 1.0, 3)),
                                           emissive_strength=float(10 ** rng.uniform(0.5, 1.5))))
        scene.add_object(name, *builtin.box(c - half, c + half), name)
    for m in scene.materials:
        m.effect = rv.Effect.SHADOWS


def _graph(restir: dict | None, light_samples: int = 1):
    import rayvr as rv

    if restir is None:
        return rv.graphs.hybrid(preset="raw", light_samples=light_samples)
    return rv.graphs.hybrid(preset="raw", direct="restir", restir=restir)


def reference(scene, views, frames: int, samples: int):
    """(reference, its relMSE): RTShadows with `samples` light samples over `frames` frames, in two
    halves from independent random streams; the halves' relMSE / 4 (trimmed) is the mean's own."""
    from rayvr.renderer import Renderer
    from rayvr.study.metrics import rel_mse_map, trimmed_mean

    halves = []
    for half in range(2):
        total = 0.0
        with Renderer(scene, _graph(None, samples), views=views, first_frame=(1 << 28) + (half << 24)) as r:
            for _ in range(max(1, frames // 2)):
                r.render()
                total = total + r.read_output("Composite.color")[..., :3].astype(np.float64)
        halves.append(total / max(1, frames // 2))
    return 0.5 * (halves[0] + halves[1]), trimmed_mean(rel_mse_map(halves[0], halves[1])) / 4


def measure(scene, views, graph, ref, display, ppd, frames: int, warmup: int, error_frames: int) -> dict:
    """GPU ms (Shadows, frame) and the mean relMSE and FLIP of single frames after `warmup`."""
    from rayvr.renderer import Renderer
    from rayvr.study.metrics import evaluate
    from rayvr.study.timing import timed_frames

    from ._timing import warm_up

    with Renderer(scene, graph, views=views) as r:
        for _ in range(warmup):
            r.render()
        errors = {"relmse_trim": [], "relmse": [], "flip": []}
        for _ in range(error_frames):
            r.render()
            img = r.read_output("Composite.color")[..., :3].astype(np.float64)
            per_view, _ = evaluate(img, ref, display, ppd, which=tuple(errors))
            for k in errors:
                errors[k].append(float(per_view[k].mean()))
        if frames > 5:   # not for smoke runs
            warm_up(r)
        timing = timed_frames(r, frames, 1)
        nonfinite = r.compiled.nonfinite_counts().get("Shadows", 0)
    return {"shadows_ms": timing.pass_ms.get("Shadows", float("nan")), "frame_ms": timing.frame_ms,
            **{k: float(np.mean(v)) for k, v in errors.items()},
            "method": timing.method, "nonfinite": nonfinite}


def at_equal_ms(rows: list[dict], ms: float, key: str) -> tuple[float, str]:
    """RTShadows' `key` error at `ms` Shadows ms: log-log interpolation between its rows, or past
    them the nearest row scaled as Monte Carlo's 1 / ms (said in the second value)."""
    pts = sorted((r["shadows_ms"], r[key]) for r in rows if r["shadows_ms"] > 0 and r[key] > 0)
    if not pts:
        return float("nan"), "no RTShadows rows"
    if ms <= pts[0][0]:
        return pts[0][1] * pts[0][0] / ms, "extrapolated below the fewest light samples"
    if ms >= pts[-1][0]:
        return pts[-1][1] * pts[-1][0] / ms, "extrapolated above the most light samples"
    for (m0, e0), (m1, e1) in zip(pts, pts[1:]):
        if m0 <= ms <= m1:
            t = (math.log(ms) - math.log(m0)) / max(math.log(m1) - math.log(m0), 1e-12)
            return math.exp((1 - t) * math.log(e0) + t * math.log(e1)), "interpolated"
    return float("nan"), "?"


@dataclass
class Plan:
    """One run's settings, from its options: what each part measures and how."""
    parts: list            # "many" and/or "scene"
    size: tuple
    samples: list          # RTShadows' light_samples rows (the scene part takes the first)
    restir_sets: list      # (name, ReSTIRDI properties), a row each
    ppd: float             # FLIP's pixels per degree
    frames: int
    warmup: int
    error_frames: int
    ref_units: int         # the progress bar's units: rendered pixel-frames
    row_units: int


def plan(args) -> Plan:
    """The run's Plan; an OptionError naming the option for a bad one."""
    from rayvr.cli.options import parse_size
    from rayvr.errors import OptionError
    from rayvr.xr.presets import get_preset

    parts = [p.strip() for p in args.parts.split(",") if p.strip()]
    if not parts or set(parts) - {"many", "scene"}:
        raise OptionError(f"--parts {args.parts}: give many, scene or both (comma-separated)")
    size = parse_size(_figure(args, "size"))
    restir_sets = _restir_sets(args.restir)
    frames, warmup, error_frames = (_figure(args, k) for k in ("frames", "warmup", "error_frames"))
    # the progress bar's ETA learns seconds per rendered pixel-frame from the steps done (a frame's
    # readback and judging cost about what its light samples do)
    pixels = args.views * size[0] * size[1]
    return Plan(parts, size, [int(s) for s in str(args.light_samples).split(",")], restir_sets,
                get_preset(args.preset).pixels_per_degree, frames, warmup, error_frames,
                pixels * _figure(args, "reference_frames"), pixels * (warmup + error_frames + frames))


def _restir_sets(text: str) -> list[tuple[str, dict]]:
    """--restir's (name, properties) rows: set names, or JSON (named by its text); OptionError if bad."""
    import json

    from rayvr.errors import OptionError, did_you_mean

    if not text.lstrip().startswith(("{", "[")):
        names = [n.strip() for n in text.split(",") if n.strip()]
        for n in names:
            if n not in RESTIR_SETS:
                raise OptionError(f"--restir: no set {n!r}{did_you_mean(n, RESTIR_SETS)}; the sets: "
                                  f"{', '.join(RESTIR_SETS)} (or give JSON properties)")
        if not names:
            raise OptionError(f"--restir: give set names ({', '.join(RESTIR_SETS)}) or JSON properties")
        return [(n, RESTIR_SETS[n]) for n in names]
    try:
        restir = json.loads(text)
    except json.JSONDecodeError as exc:
        raise OptionError(f"--restir: not JSON ({exc.msg}); give an object such as '{{\"candidates\": 4}}' "
                          f"or a list of them, or set names") from None
    sets = restir if isinstance(restir, list) else [restir]
    if not sets or not all(isinstance(r, dict) for r in sets):
        raise OptionError("--restir: give a JSON object of ReSTIRDI properties or a non-empty list of them")
    return [(json.dumps(r) if r else "defaults", r) for r in sets]


def run(args) -> dict:
    from rayvr.study.progress import StudyProgress

    settings = plan(args)
    rows, notes, method = [], [], "?"
    progress = StudyProgress(desc="restir")
    for part in settings.parts:
        measured = (len(settings.samples) if part == "many" else 1) + len(settings.restir_sets)
        progress.plan("render", settings.ref_units + measured * settings.row_units)
    with progress:
        for part in settings.parts:
            method = _part(args, part, settings, progress, rows, notes) or method
    notes.append(f"timing: {method}; errors: {settings.error_frames} single frames after {settings.warmup}, FLIP at "
                 f"{settings.ppd:.1f} ppd ({args.preset})")
    return {"columns": COLUMNS, "rows": rows, "notes": notes}


def _part(args, part: str, settings: Plan, progress, rows: list, notes: list) -> str | None:
    """One part's rows (many or scene) into `rows` and `notes`; its timing method."""
    import rayvr as rv
    from rayvr.cli.options import load_scene_arg
    from rayvr.study.display import Display
    from rayvr.xr.cameras import default_views

    s = settings
    scene = load_scene_arg(args.scene)
    if part == "many":
        add_many_lights(scene, _figure(args, "lights"), _figure(args, "emitters"), args.seed)
        label = f"{scene.name} + {_figure(args, 'lights')} lights, {_figure(args, 'emitters')} emitters"
    else:
        for m in scene.materials:
            m.effect = rv.Effect.SHADOWS
        label = scene.name
    shape = f"{args.views}x{s.size[0]}x{s.size[1]}"
    views = default_views(scene, args.views, s.size)
    with progress.step("render", s.ref_units, f"{part}: reference"):
        ref, ref_noise = reference(scene, views, _figure(args, "reference_frames"),
                                   _figure(args, "reference_samples"))
    notes.append(f"{part}: reference relMSE (its halves' / 4) {ref_noise:.3g}")
    display = Display().fixed(ref)

    def measured(graph, label_: str) -> dict:
        with progress.step("render", s.row_units, f"{part}: {label_}"):
            return measure(scene, views, graph, ref, display, s.ppd, s.frames, s.warmup, s.error_frames)

    plain, method = [], None
    for n in s.samples if part == "many" else s.samples[:1]:
        m = measured(_graph(None, n), f"RTShadows x{n}")
        plain.append(m)
        method = m["method"]
        rows.append([part, label, f"RTShadows light_samples={n}", shape, round(m["shadows_ms"], 3),
                     round(m["frame_ms"], 3), m["relmse_trim"], m["relmse"], m["flip"], ""])
    for set_name, props in s.restir_sets:
        m = measured(_graph(props), f"ReSTIR {set_name}")
        rows.extend(_restir_rows(part, label, shape, set_name, plain, ref_noise, notes, m))
    return method


def _restir_rows(part, label, shape, set_name: str, plain: list[dict], ref_noise: float, notes: list, m: dict) -> list:
    """The table rows of one ReSTIRDI property set's measurement `m` against the RTShadows rows
    `plain` of the same part, its target's ratio row and note."""
    name = f"ReSTIRDI {set_name}"
    if m["nonfinite"]:
        notes.append(f"{part}: {name} set {m['nonfinite']} non-finite samples to 0")
    rows = [[part, label, name, shape, round(m["shadows_ms"], 3), round(m["frame_ms"], 3), m["relmse_trim"],
             m["relmse"], m["flip"], ""]]
    if part == "many":
        for row in (*plain, m):   # each error less the reference's own, which adds to it
            row["relmse_own"] = max(row["relmse_trim"] - ref_noise, 1e-9)
        if ref_noise > 0.5 * min(row["relmse_trim"] for row in (*plain, m)):
            notes.append("many: the reference's own relMSE is over half a row's: raise --reference-samples or "
                         "--reference-frames before reading the ratio")
        want, how = at_equal_ms(plain, m["shadows_ms"], "relmse_own")
        ratio = m["relmse_own"] / want
        rows.append([part, label, "ReSTIR / RTShadows relMSE at equal Shadows ms", shape, round(m["shadows_ms"], 3),
                     "", round(ratio, 4), "", "", how])
        notes.append(f"many, {name}: relMSE ratio at equal Shadows ms (less the reference's) {ratio:.3f} (target <= "
                     f"{TARGET_RELMSE_RATIO}: {'met' if ratio <= TARGET_RELMSE_RATIO else 'not met'})")
    else:
        flip_ratio, ms_ratio = m["flip"] / plain[0]["flip"], m["frame_ms"] / plain[0]["frame_ms"]
        rows.append([part, label, "ReSTIR / plain SHADOWS: FLIP, frame ms", shape, "", round(ms_ratio, 4), "", "",
                     round(flip_ratio, 4), ""])
        met = flip_ratio <= TARGET_FLIP_RATIO and ms_ratio <= TARGET_MS_RATIO
        notes.append(f"scene, {name}: FLIP ratio {flip_ratio:.3f} (target <= {TARGET_FLIP_RATIO}) at frame ms ratio "
                     f"{ms_ratio:.3f} (target <= {TARGET_MS_RATIO}): {'met' if met else 'not met'}")
    return rows
