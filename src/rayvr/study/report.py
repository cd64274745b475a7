"""The error study's report: one folder, written atomically (rayvr.fileio.atomic_folder).

    DIR/report.md        the tables, the verdicts, links to the images
    DIR/report.html      the same, self-contained: every image and plot inline (base64 PNG)
    DIR/results.json     Results.as_dict() (docs/CONTRACTS.md)
    DIR/pareto.png       displayed-image FLIP against GPU ms: each configuration (its spread as a
                         bar, its bias floor as a hollow marker), the Pareto front, the budget
    DIR/convergence.png  error against accumulated wall and GPU time of the progressive renders
    DIR/images/          the reference and each configuration as displayed (views side by side),
                         with per-pixel error maps: FLIP (magma, 0..1) and relative RMS error
                         sqrt(relMSE) (magma, 0..100%)

Both documents are built from one list of sections, so they say the same.
"""
from __future__ import annotations

import base64
import html
import re
from pathlib import Path

import numpy as np

from ..fileio import atomic_folder, atomic_write, png_bytes, write_text
from .display import Display, to_uint8
from .metrics import DESCRIPTIONS, LOWER_IS_BETTER, METRICS
from .reference import PIXEL_FILTER
from .results import fmt, markdown_table


def slug(name: str) -> str:
    """A file name for a configuration: lowercase letters, digits and '-'."""
    return re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or "config"


def side_by_side(views: np.ndarray) -> np.ndarray:
    """(views, h, w, c) -> (h, views * w, c), view 0 on the left."""
    return np.concatenate(list(views), axis=1)


def colour_map(values: np.ndarray, vmax: float = 1.0) -> np.ndarray:
    """(views, h, w) values in [0, vmax] as magma uint8 RGB, views side by side."""
    from matplotlib import colormaps

    rgba = colormaps["magma"](np.clip(np.asarray(values, dtype=np.float64) / vmax, 0.0, 1.0))
    return side_by_side((rgba[..., :3] * 255 + 0.5).astype(np.uint8))


class _Images:
    """PNGs of the report: written under images/ and kept as bytes for the HTML; with `step` > 1
    every step-th pixel of each view, row and column (smaller documents; the metrics are of the
    full images)."""

    def __init__(self, folder: Path, display: Display, step: int = 1):
        self.folder, self.display, self.data, self.step = folder, display, {}, max(1, int(step))

    def thin(self, views: np.ndarray) -> np.ndarray:
        """(views, h, w, ...) at every step-th row and column."""
        return np.asarray(views)[:, ::self.step, ::self.step]

    def errors(self, name: str, values: np.ndarray, vmax: float = 1.0) -> str:
        """A per-pixel error map (views, h, w) in magma."""
        return self.add(name, colour_map(self.thin(values), vmax))

    def add(self, name: str, pixels: np.ndarray) -> str:
        rel = f"images/{name}.png"
        data = png_bytes(pixels)
        atomic_write(self.folder / rel, lambda tmp: tmp.write_bytes(data))
        self.data[rel] = data
        return rel

    def shown(self, name: str, linear: np.ndarray) -> str:
        return self.add(name, side_by_side(to_uint8(self.display(self.thin(linear)))))


def _figure():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.2, 4.8), dpi=110)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: Path) -> bytes:
    import io

    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png")
    data = buf.getvalue()
    atomic_write(path, lambda tmp: tmp.write_bytes(data))
    return data


def pareto_plot(results, path: Path, metric: str = "flip", budget_ms: float | None = None) -> bytes:
    """`metric` (mean, spread as error bars) against GPU ms per configuration, hollow markers at
    the bias floors, the Pareto front, a line at `budget_ms`; PNG bytes (also written to path)."""
    fig = _figure()
    ax = fig.add_subplot()
    rows = results.rows
    xs = [r.gpu_ms for r in rows]
    ys = [r.mean(metric) for r in rows]
    es = [r.errors[metric]["std"] for r in rows]
    colours = ["tab:red" if r.tuned else "tab:blue" for r in rows]
    ax.errorbar(xs, ys, yerr=es, fmt="none", ecolor="gray", elinewidth=1, capsize=2, zorder=2)
    ax.scatter(xs, ys, c=colours, zorder=3, label="static view (mean ± std)")
    floors = [(r.gpu_ms, r.floor[metric]) for r in rows if r.floor and metric in r.floor]
    if floors:
        ax.scatter(*zip(*floors), facecolors="none", edgecolors="tab:green", zorder=3, label="bias floor (converged)")
    for i, (r, x, y) in enumerate(zip(rows, xs, ys)):
        ax.annotate(r.name, (x, y), textcoords="offset points", xytext=(5, 4 - 9 * (i % 3)), fontsize=7)
    front = results.pareto(metric)
    ax.plot([r.gpu_ms for r in front], [r.mean(metric) for r in front], "--", lw=1, color="gray",
            label="Pareto front", zorder=1)
    if budget_ms:
        ax.axvline(budget_ms, color="red", lw=1, label=f"budget {budget_ms:g} ms")
    if min(xs) > 0 and max(xs) > 20 * min(xs):
        ax.set_xscale("log")
    better = "lower" if LOWER_IS_BETTER[metric] else "higher"
    ax.set_xlabel(f"GPU ms per frame ({results.method})")
    ax.set_ylabel(f"{METRICS[metric]} of the displayed image ({better} is better)")
    s = results.study
    ax.set_title(f"{s['scene']}: {s['views']} x {s['size'][0]}x{s['size'][1]}, FLIP at {s['ppd']:.1f} ppd",
                 fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, path)


def convergence_plot(results, path: Path) -> bytes:
    """FLIP and relMSE of each progressive render against accumulated wall (solid) and GPU
    (dashed) seconds, log-log, with the reference's own predicted relMSE."""
    fig = _figure()
    panels = [m for m in ("flip", "relmse") if all(m in p for c in results.curves for p in c.points)]
    for k, metric in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        for c in results.curves:
            line, = ax.plot([p["wall_s"] for p in c.points], [p[metric] for p in c.points], marker="o", ms=3,
                            label=f"{c.name} (wall)")
            ax.plot([p["gpu_s"] for p in c.points], [p[metric] for p in c.points], "--", color=line.get_color(),
                    label=f"{c.name} (GPU)")
        if metric == "relmse" and results.reference is not None:
            ax.axhline(results.reference.noise_relmse, color="gray", lw=1, label="reference's own noise")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("accumulated seconds")
        ax.set_ylabel(METRICS[metric])
        ax.grid(True, alpha=0.3, which="both")
        ax.legend(fontsize=6)
    return _save(fig, path)


def sections(results, images: _Images, plots: dict, budget_ms=None, title: str | None = None) -> list:
    """The report's content: [(heading, [block, ...]), ...]; blocks are ("p", text),
    ("list", [text]), ("table", cols, rows), ("images", [(path, caption)])."""
    s, ref = results.study, results.reference
    st = s["settings"]
    out = []
    intro = [("p", f"{s['views']} view(s) of {s['size'][0]}x{s['size'][1]} on {s['device']}; GPU time by "
                   f"{s['timing']} (warm-up {s['warmup_s']:g} s before timing). The study took "
                   f"{s['seconds']:.0f} s.")]
    intro.append(("p", f"**Reference**: {ref.verdict()}."))
    for frame, r in results.motion_references:
        intro.append(("p", f"**Reference of trajectory frame {frame}**: {r.verdict()}."))
    if s.get("notes"):
        intro.append(("list", list(s["notes"])))
    out.append((title or f"Error against GPU time: {s['scene']}", intro))
    rs = ref.settings
    seeds = ref.as_dict()["seeds"]
    cap = (f"rendered {rs.frames} frames at a time until converged, at most {rs.max_frames} frames"
           + (f" or {rs.max_seconds:g} s of rendering" if rs.max_seconds is not None else "")
           if rs.extends else "a fixed frame count")
    ref_blocks = [("list", [
        f"{ref.name}: every pixel path traced from the camera, each path from a random point of its pixel "
        f"(pixel filter: {PIXEL_FILTER}), {ref.frames} frames x {rs.spp} spp = {ref.samples_per_pixel} paths per "
        f"pixel ({cap}; {ref.stopped()}), up to {rs.max_bounces} bounces (each scattering vertex samples a "
        f"light), Russian roulette from bounce 3.",
        "Seeds: frames " + ", ".join(f"{a}..{b - 1}" for a, b in seeds["half_a_rounds"]) + " (half A) and "
        + ", ".join(f"{a}..{b - 1}" for a, b in seeds["half_b_rounds"]) + " (half B); the configurations use "
        "frames from 0, so no render shares random numbers with the reference.",
        ("**Halves identical**: the two halves are equal to the bit, so the convergence check cannot tell "
         "noise-free light at these settings from a half that was not rendered." if ref.halves_identical else
         f"**{'Converged' if ref.converged else 'NOT converged'}**: the halves predict a relMSE of "
         f"{ref.noise_relmse:.2e} for their mean against the truth (mean((A-B)^2/4 / (M^2+eps)), eps {ref.eps:g}); "
         f"tolerance {rs.tolerance:.0e}, an RMS error of {100 * rs.tolerance ** 0.5:.1f}% of a pixel's radiance."
         + ("" if ref.converged else f" About {ref.frames_to_converge()} frames of {rs.spp} spp would converge.")),
        f"**{'Enough' if ref.bounces_enough else 'Too few'} bounces**: one more bounce changes the mean radiance by "
        f"{100 * ref.bounce_change:+.3f}% (tolerance {100 * rs.bounce_tolerance:g}%; rendered over "
        f"{rs.bounce_check_frames} frames with half A's random numbers, so only the extra bounce differs).",
        "Half A against half B (each half the paths): " + ", ".join(
            f"{METRICS[m]} {fmt(v, 3)}" for m, v in s.get("reference_halves", {}).items())
        + ": the smallest error this reference can tell apart from its own noise.",
        f"Source: {ref.source}."])]
    ref_blocks.append(("images", [(images.shown("reference", ref.image), "reference (displayed)"),
                                  (images.errors("reference-noise", np.sqrt(ref.noise_map())),
                                   "its predicted relative RMS error per pixel, from the halves (0..100%)")]))
    if results.motion_references:
        ref_blocks.append(("list", [f"Trajectory frame {i}: {r.verdict()}" for i, r in results.motion_references]))
    out.append(("Reference", ref_blocks))
    motion = st.get("motion")
    how = [f"{METRICS[m]}: {DESCRIPTIONS[m]}" for m in s["metric_descriptions"]]
    how += [f"Displayed image: {s['display_text']} (CPU, the curves of tonemap.comp; one fixed exposure for test "
            f"and reference, not quantised).",
            f"Pixels per degree: {s['ppd']:.1f}, {s['ppd_source']}; relMSE eps {s['eps']:g}.",
            f"Static view: {st['frames']} judged frames per configuration (each after its own accumulation; the "
            f"first after {st['warmup'] + st['timing_frames']} frames of history, a count that no GPU's speed "
            f"changes), mean ± sample standard deviation over those frames and the views; GPU ms over {st['timing_frames']} "
            f"timed frames after {st['warmup']} untimed."
            + (f" HDR-FLIP (FLIP at many exposures, the costliest metric) on the first {st['hdrflip_frames']} of "
               f"the judged frames only, not in motion, on the floors nor on the progressive curves."
               if st.get("hdrflip_frames") else "")
            + (f" The images were judged by {s['metric_workers']} worker processes while the GPU rendered on "
               f"(the same numbers as judged one after the other)." if s.get("metric_workers") else "")]
    if motion:
        how.append(f"In motion: the views carried along the '{motion['trajectory']}' trajectory at "
                   f"{motion['refresh_hz']:g} Hz for {motion['frames']} frames; frames {motion['sampled_frames']} "
                   f"judged, each against its own reference (same settings, own seeds).")
    how.append("The reference is pixel-filtered (a box over each pixel, what a displayed pixel integrates); the "
               "G-buffers sample pixel centres, so a configuration that does not anti-alias shows its aliasing at "
               "edges, most at the light's, in its error and its floor, and one that resolves sub-pixel jitter "
               "(TAA, SVGF) converges to the filtered image.")
    if st.get("floors"):
        how.append(f"Bias floor: each configuration rendered converged ({100 * st['floor_fraction']:g}% of the "
                   f"reference's paths per pixel, its own seeds) against the reference: its relMSE, and the part "
                   f"of it that noise does not explain (relMSE - predicted noise of both; 'within noise' when "
                   f"relMSE <= twice the noise). What is left is light the configuration leaves out.")
    out.append(("How the error is measured", [("list", how)]))
    res = [("p", f"**{results.table_title()}**"), ("table", *results.table_data())]
    res.append(("p", "Settings of each configuration:"))
    res.append(("table", *results.settings_data()))
    res.append(("images", [(plots["pareto"], "displayed-image FLIP against GPU ms")]))
    out.append(("Results", res))
    if results.tuned is not None:
        t = results.tuned
        cols = ["material", "effect", "pixels", "predicted ms", f"predicted {t.model.metric}"]
        rows = [[m, e.name, str(t.model.pixels.get(m, "-")), fmt(t.model.ms[m][e]), fmt(t.model.error[m][e])]
                for m, e in t.assignment.items()]
        text = (f"budget {t.budget_ms:g} ms: predicted {t.predicted_ms:.4g} ms, {t.model.metric} "
                f"{t.predicted_error:.4g}" + ("" if t.fits else " (does NOT fit)"))
        if t.measured_ms is not None:
            text += f"; measured {t.measured_ms:.4g} ms ({t.method}), {t.model.metric} {t.measured_error:.4g}"
        out.append(("Tuned assignment", [("p", text), ("table", cols, rows), ("list", list(t.notes))]))
    if results.curves:
        out.append(("Progressive convergence", [
            ("p", "Error against accumulated time of a progressive render (1 spp per frame, the reference's "
                  "bounces, accumulated), read after 1, 2, 4, ... frames. Wall seconds measured (GPU finished, "
                  "readbacks not counted); GPU seconds = frames x the GPU ms per frame timed first."),
            ("table", *results.curve_data()),
            ("images", [(plots["convergence"], "error against accumulated wall (solid) and GPU (dashed) seconds")])]))
    gallery = []
    if images.step > 1:
        gallery.append(("p", f"Images at every {images.step}th pixel of each row and column (the metrics are of the "
                             f"full images)."))
    for r in results.rows:
        if r.image is None:
            continue
        name = slug(r.name)
        shots = [(images.shown(name, r.image), f"{r.name} (displayed)")]
        if "flip" in r.maps:
            shots.append((images.errors(f"{name}-flip", r.maps["flip"]), "FLIP per pixel (0..1)"))
        if "relmse" in r.maps:
            shots.append((images.errors(f"{name}-relmse", np.sqrt(r.maps["relmse"])),
                          "relative RMS error per pixel (0..100%)"))
        if r.floor_image is not None:
            shots.append((images.shown(f"{name}-floor", r.floor_image), "converged (bias floor)"))
        gallery.append(("p", f"**{r.name}**: GPU {fmt(r.gpu_ms)} ms, FLIP {fmt(r.errors.get('flip', {}).get('mean'))}"))
        gallery.append(("images", shots))
    out.append(("Images", gallery))
    return out


def to_markdown(secs) -> str:
    lines = []
    for level, (heading, blocks) in enumerate(secs):
        lines += [("# " if level == 0 else "## ") + heading, ""]
        for block in blocks:
            kind = block[0]
            if kind == "p":
                lines += [block[1], ""]
            elif kind == "list":
                lines += [f"- {item}" for item in block[1]] + [""]
            elif kind == "table":
                lines += [markdown_table(block[1], block[2]), ""]
            elif kind == "images":
                lines += [" ".join(f"![{cap}]({path})" for path, cap in block[1]), ""]
    return "\n".join(lines).rstrip() + "\n"


STYLE = """body{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 6px}
th{background:#f3f3f3}figure{display:inline-block;margin:0.3em;vertical-align:top}
figcaption{font-size:0.75em;max-width:24em}img.px{image-rendering:pixelated;min-width:256px}"""


def _inline(text: str) -> str:
    return re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", html.escape(text))


def to_html(secs, data: dict) -> str:
    """Self-contained HTML: images as data URIs from `data` (path -> PNG bytes)."""
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'>", f"<title>{html.escape(secs[0][0])}</title>",
             f"<style>{STYLE}</style></head><body>"]
    for level, (heading, blocks) in enumerate(secs):
        tag = "h1" if level == 0 else "h2"
        parts.append(f"<{tag}>{html.escape(heading)}</{tag}>")
        for block in blocks:
            kind = block[0]
            if kind == "p":
                parts.append(f"<p>{_inline(block[1])}</p>")
            elif kind == "list":
                parts.append("<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in block[1]) + "</ul>")
            elif kind == "table":
                head = "".join(f"<th>{html.escape(c)}</th>" for c in block[1])
                body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>"
                               for row in block[2])
                parts.append(f"<table><tr>{head}</tr>{body}</table>")
            elif kind == "images":
                for path, cap in block[1]:
                    uri = "data:image/png;base64," + base64.b64encode(data[path]).decode()
                    cls = "" if path.endswith(("pareto.png", "convergence.png")) else " class='px'"
                    parts.append(f"<figure><img{cls} src='{uri}' alt='{html.escape(cap)}'>"
                                 f"<figcaption>{html.escape(cap)}</figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(results, folder, budget_ms: float | None = None, title: str | None = None, extra=None,
                 image_step: int = 1) -> Path:
    """Write the report folder (module docstring) atomically; returns its path. `extra`:
    {relative name: text} more files to put in it (e.g. the tuner's JSON). `image_step`: the
    images at every image_step-th pixel (e.g. 8 for 2 x 1440x1600: the report stays a few MB)."""
    with atomic_folder(folder) as tmp:
        d = results.study["display"]
        images = _Images(tmp, Display(d["operator"], d["exposure_stops"]), image_step)
        if images.step > 1:
            results.study["report_image_step"] = images.step
        plots = {"pareto": "pareto.png"}
        images.data["pareto.png"] = pareto_plot(results, tmp / "pareto.png", "flip" if "flip" in results.metrics()
                                                else results.metrics()[0], budget_ms)
        if results.curves:
            plots["convergence"] = "convergence.png"
            images.data["convergence.png"] = convergence_plot(results, tmp / "convergence.png")
        secs = sections(results, images, plots, budget_ms, title)
        write_text(tmp / "results.json", results.to_json())
        write_text(tmp / "report.md", to_markdown(secs))
        write_text(tmp / "report.html", to_html(secs, images.data))
        for name, text in (extra or {}).items():
            write_text(tmp / name, text)
    return Path(folder)
