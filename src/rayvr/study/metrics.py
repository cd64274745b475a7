"""Image error metrics against a reference: FLIP, HDR-FLIP, relative MSE, PSNR and SSIM.

Images are numpy arrays shaped (views, h, w, c) (also accepted: (h, w, c) and (h, w)); only the
first three channels count (alpha is ignored; one channel is grey). Float images are linear
radiance (HDR); integer images (uint8/uint16) are display-encoded (LDR, sRGB). A NaN or Inf in
an image is an error that names the image and the first bad pixel, never a silent NaN metric.

    flip(test, ref)           mean FLIP (NVIDIA's flip-evaluator), HDR-FLIP for float, LDR-FLIP for integer
    rel_mse(test, ref)        mean over pixels and channels of (t - r)^2 / (r^2 + eps)
    trimmed_mean(map)         a per-pixel map's mean without its largest 0.1% (relMSE that outliers do not rule)
    firefly_map(test, ref)    pixels whose luminance exceeds FIREFLY_RATIO x the reference's
    psnr(test, ref, peak)     10 log10(peak^2 / MSE) in dB; inf for identical images
    ssim(test, ref)           scikit-image's structural similarity of display-encoded images

`evaluate` is the error study's set: FLIP, PSNR and SSIM of the displayed images (see
rayvr.study.display), HDR-FLIP, relMSE, trimmed relMSE and the firefly count of the linear radiance;
given each pixel's eccentricity (degrees from the view's centre: rayvr.xr.foveation), also FLIP
within the foveal radius and FLIP weighted by eccentricity, which judge a foveated render where
the eye looks.

The `*_map` functions return the per-pixel error (views, h, w) whose mean is the metric: the
budget tuner sums them over each material's pixels.
"""
from __future__ import annotations

import math
import os

import numpy as np

from .. import images
from ..errors import OptionError, RayvrError
from ..xr import foveation
from .display import LUMINANCE

DYNAMIC_RANGES = ("auto", "ldr", "hdr")
THREADED_VIEW_PIXELS = 256 * 256   # smaller views: starting threads costs more than it saves


def as_views(image, name: str = "image") -> np.ndarray:
    """`image` as a (views, h, w, c) array (no copy when it already is one)."""
    a = np.asarray(image)
    if a.ndim == 2:
        a = a[None, :, :, None]
    elif a.ndim == 3:
        a = a[None]
    if a.ndim != 4 or 0 in a.shape:
        raise OptionError(f"{name}: shape {np.shape(image)} is not an image; expected (views, h, w, c), "
                          f"(h, w, c) or (h, w) with no empty axis")
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise OptionError(f"{name}: dtype {a.dtype} is not a number type; pass float or uint8/uint16 pixels")
    return a


def check_finite(a: np.ndarray, name: str) -> None:
    """Raise naming `name` and its first NaN/Inf pixel (view, y, x, channel) if there is one."""
    if not np.issubdtype(a.dtype, np.floating):
        return
    bad = ~np.isfinite(a)
    if bad.any():
        v, y, x, c = (int(i) for i in np.argwhere(bad)[0])
        raise RayvrError(f"{name}: {int(bad.sum())} NaN/Inf value(s), the first {a[v, y, x, c]} at view {v}, "
                         f"row {y}, column {x}, channel {c}; the renderer produced invalid radiance there "
                         f"(an image metric of it would be meaningless)")


def pair(test, reference, names=("test", "reference")) -> tuple[np.ndarray, np.ndarray]:
    """Validated (views, h, w, 3) float64 copies of `test` and `reference` (same shape, finite)."""
    t, r = as_views(test, names[0]), as_views(reference, names[1])
    if t.shape[:3] != r.shape[:3]:
        raise OptionError(f"{names[0]} is {t.shape[0]} view(s) of {t.shape[2]}x{t.shape[1]} but {names[1]} is "
                          f"{r.shape[0]} of {r.shape[2]}x{r.shape[1]}; compare images of the same size and views")
    check_finite(t, names[0])
    check_finite(r, names[1])
    return rgb(t), rgb(r)


def rgb(a: np.ndarray) -> np.ndarray:
    """First three channels as float64 (one channel repeated); integer pixels scaled to [0, 1]."""
    out = a.astype(np.float64)
    if np.issubdtype(a.dtype, np.integer):
        out /= float(np.iinfo(a.dtype).max)
    if out.shape[-1] < 3:
        out = np.repeat(out[..., :1], 3, axis=-1)
    return out[..., :3]


# -- relative MSE and PSNR ------------------------------------------------------------------
def rel_mse_map(test, reference, eps: float = 1e-2, names=("test", "reference")) -> np.ndarray:
    """Per-pixel relative squared error (views, h, w): channel mean of (t - r)^2 / (r^2 + eps)."""
    if not eps > 0:
        raise OptionError(f"rel_mse: eps must be > 0 (it keeps black reference pixels finite), got {eps!r}")
    t, r = pair(test, reference, names)
    return ((t - r) ** 2 / (r * r + eps)).mean(axis=-1)


def rel_mse(test, reference, eps: float = 1e-2, names=("test", "reference")) -> float:
    """Relative mean squared error: the mean over pixels and RGB channels of (t - r)^2 / (r^2 + eps)."""
    return float(rel_mse_map(test, reference, eps, names).mean())


TRIM_FRACTION = 1e-3   # the share of largest per-pixel errors a trimmed mean leaves out
FIREFLY_RATIO = 10.0   # a firefly: luminance above this multiple of the reference's


def trimmed_mean(error_map, fraction: float = TRIM_FRACTION) -> float:
    """The mean of `error_map` without its largest `fraction` of values (the denoising
    literature's outlier-robust relMSE: a few firefly pixels cannot rule it)."""
    flat = np.asarray(error_map, dtype=np.float64).ravel()
    drop = int(flat.size * fraction)
    if drop == 0:
        return float(flat.mean())
    keep = flat.size - drop
    return float(np.partition(flat, keep - 1)[:keep].mean())


def firefly_map(test, reference, eps: float = 1e-2, names=("test", "reference")) -> np.ndarray:
    """Per pixel (views, h, w), 1 where the test's luminance exceeds FIREFLY_RATIO times the
    reference's: lum(t) - lum(r) > (FIREFLY_RATIO - 1) sqrt(lum(r)^2 + eps), with relMSE's
    `eps`, so that a black reference pixel needs radiance above about (RATIO - 1) sqrt(eps)."""
    t, r = pair(test, reference, names)
    lt, lr = t @ LUMINANCE, r @ LUMINANCE
    return (lt - lr > (FIREFLY_RATIO - 1.0) * np.sqrt(lr * lr + eps)).astype(np.float64)


def default_peak(a: np.ndarray) -> float:
    return float(np.iinfo(a.dtype).max) if np.issubdtype(a.dtype, np.integer) else 1.0


def psnr(test, reference, peak: float | None = None, names=("test", "reference")) -> float:
    """Peak signal-to-noise ratio in dB over RGB: 10 log10(peak^2 / MSE); inf when identical.

    `peak` is in the images' own units: default 255 for uint8 (65535 for uint16), 1.0 for float.
    """
    t, r = as_views(test, names[0]), as_views(reference, names[1])
    if peak is None:
        peak = default_peak(r)
    if not (isinstance(peak, (int, float)) and math.isfinite(peak) and peak > 0):
        raise OptionError(f"psnr: peak must be a finite number > 0 (the largest pixel value), got {peak!r}")
    tf, rf = pair(t, r, names)
    scale = float(np.iinfo(r.dtype).max) if np.issubdtype(r.dtype, np.integer) else 1.0
    mse = float(((tf - rf) ** 2).mean()) * scale * scale   # back in the images' own units
    return math.inf if mse == 0.0 else 10.0 * math.log10(peak * peak / mse)


# -- FLIP ------------------------------------------------------------------------------------
def flip_map(test, reference, dynamic_range: str = "auto", ppd: float | None = None,
             names=("test", "reference")) -> np.ndarray:
    """Per-pixel FLIP error (views, h, w) in [0, 1], each view evaluated on its own.

    `dynamic_range`: "hdr" (linear radiance, HDR-FLIP over the reference's exposure range),
    "ldr" (sRGB-encoded values in [0, 1] or integers), or "auto" (HDR for float, LDR for integer
    images). `ppd`: pixels per degree of the display (FLIP's default 67 is a desktop monitor;
    a VR headset is about 15-25)."""
    import flip_evaluator

    t0, r0 = as_views(test, names[0]), as_views(reference, names[1])
    mode = str(dynamic_range).lower()
    if mode not in DYNAMIC_RANGES:
        raise OptionError(f"flip: dynamic_range {dynamic_range!r}; use one of {', '.join(DYNAMIC_RANGES)}")
    if mode == "auto":
        mode = "hdr" if np.issubdtype(r0.dtype, np.floating) else "ldr"
    params = {}
    if ppd is not None:
        if not ppd > 0:
            raise OptionError(f"flip: ppd (pixels per degree) must be > 0, got {ppd!r}")
        params["ppd"] = float(ppd)
    t, r = pair(t0, r0, names)
    for img, name in ((t, names[0]), (r, names[1])):
        if (img < 0).any():
            raise RayvrError(f"{name}: {int((img < 0).sum())} negative value(s) (min {img.min():.3g}); FLIP needs "
                             f"non-negative radiance: the renderer wrote invalid colour")
        if mode == "ldr" and img.max() > 1.0:
            raise OptionError(f"{name}: values up to {img.max():.3g} in LDR mode; LDR-FLIP takes sRGB values in "
                              f"[0, 1] (or integers); use dynamic_range='hdr' for linear radiance")
    def one_view(v: int) -> np.ndarray:
        tv, rv = (np.ascontiguousarray(a[v], dtype=np.float32) for a in (t, r))
        return _flip_view(flip_evaluator, tv, rv, mode, params)

    if t.shape[0] == 1 or t.shape[1] * t.shape[2] < THREADED_VIEW_PIXELS:
        return np.stack([one_view(v) for v in range(t.shape[0])])
    # HDR-FLIP of a 1440x1600 view takes seconds of CPU; views run in threads.
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(min(t.shape[0], os.cpu_count() or 1)) as pool:
        return np.stack(list(pool.map(one_view, range(t.shape[0]))))


def _flip_view(flip_evaluator, test: np.ndarray, ref: np.ndarray, mode: str, params: dict) -> np.ndarray:
    if mode == "hdr" and not ref.any():
        # flip-evaluator derives the exposure range from the reference and ends the process when
        # the reference is all black; take the range from the test image instead.
        if not test.any():
            return np.zeros(test.shape[:2], np.float32)
        _, _, derived = flip_evaluator.evaluate(test, test, "HDR", applyMagma=False, computeMeanError=False,
                                                parameters=dict(params))
        params = {**params, **{k: derived[k] for k in ("startExposure", "stopExposure", "numExposures")}}
    error_map, _, _ = flip_evaluator.evaluate(ref, test, mode.upper(), applyMagma=False, computeMeanError=False,
                                              parameters=dict(params))
    return np.asarray(error_map, dtype=np.float32).reshape(test.shape[:2])


def flip(test, reference, dynamic_range: str = "auto", ppd: float | None = None,
         names=("test", "reference")) -> float:
    """Mean FLIP error in [0, 1] (0 = identical); see `flip_map` for the options."""
    return float(flip_map(test, reference, dynamic_range, ppd, names).mean())


# -- SSIM ------------------------------------------------------------------------------------
def ssim(test, reference, names=("test", "reference")) -> float:
    """Mean structural similarity (scikit-image: uniform 7x7 windows, RGB as channels,
    data_range 1) of display-encoded images in [0, 1], averaged over views; 1 = identical."""
    return float(np.mean(ssim_views(test, reference, names)))


def ssim_views(test, reference, names=("test", "reference")) -> np.ndarray:
    """SSIM per view (views,) of display-encoded images in [0, 1]."""
    from skimage.metrics import structural_similarity

    t, r = pair(test, reference, names)
    if min(t.shape[1:3]) < 7:
        raise OptionError(f"ssim: views of {t.shape[2]}x{t.shape[1]} pixels are smaller than SSIM's 7x7 window; "
                          f"measure at least 7x7 pixels")
    return np.array([structural_similarity(t[v], r[v], channel_axis=-1, data_range=1.0) for v in range(len(t))])


# -- display encoding (for PSNR of display-referred images) -----------------------------------
def srgb_encode(linear) -> np.ndarray:
    """Linear radiance clamped to [0, 1] and sRGB-encoded (float64): what a display shows at exposure 0."""
    return images.srgb_encode(np.asarray(linear, dtype=np.float64))


# -- the study's metrics ----------------------------------------------------------------------
METRICS = {"flip": "FLIP", "hdrflip": "HDR-FLIP", "psnr": "PSNR dB", "ssim": "SSIM", "relmse": "relMSE",
           "relmse_trim": "relMSE trim 0.1%", "fireflies": "fireflies", "flip_fovea": "FLIP fovea",
           "flip_ecc": "FLIP ecc-weighted"}
# The FLIP map judged by where each pixel lies from the view's centre (they need its eccentricity).
FOVEAL_METRICS = ("flip_fovea", "flip_ecc")
IMAGE_METRICS = tuple(m for m in METRICS if m not in FOVEAL_METRICS)   # what the images alone give
FOVEAL_RADIUS_DEG = foveation.DEFAULT_RADIUS_DEG
DESCRIPTIONS = {"flip": "LDR-FLIP of the displayed images at the headset's pixels per degree",
                "hdrflip": "HDR-FLIP of the linear radiance at the same pixels per degree",
                "psnr": "PSNR of the displayed images (peak 1)",
                "ssim": "SSIM of the displayed images (scikit-image, data_range 1)",
                "relmse": "relative MSE of the linear radiance, (t - r)^2 / (r^2 + eps), eps stated",
                "relmse_trim": f"relMSE without the largest {100 * TRIM_FRACTION:g}% of per-pixel errors (robust "
                               f"to fireflies)",
                "fireflies": f"pixels per view whose luminance exceeds {FIREFLY_RATIO:g}x the reference's "
                             f"(lum(t) - lum(r) > {FIREFLY_RATIO - 1:g} sqrt(lum(r)^2 + eps))",
                "flip_fovea": f"LDR-FLIP of the displayed images within {FOVEAL_RADIUS_DEG:g} degrees of each view's "
                              f"centre (the central {2 * FOVEAL_RADIUS_DEG:g} degrees: where a fixed foveation keeps "
                              f"every ray)",
                "flip_ecc": f"LDR-FLIP weighted by eccentricity e from each view's centre: 1 within "
                            f"{FOVEAL_RADIUS_DEG:g} degrees, ({FOVEAL_RADIUS_DEG:g} / e)^2 beyond (the fall-off the "
                            f"foveated ray budget assumes)"}
LOWER_IS_BETTER = {"flip": True, "hdrflip": True, "psnr": False, "ssim": False, "relmse": True,
                   "relmse_trim": True, "fireflies": True, "flip_fovea": True, "flip_ecc": True}
RELMSE_METRICS = ("relmse", "relmse_trim")   # the means of the per-pixel relMSE map
MAP_METRICS = ("flip", "relmse")   # per-pixel maps whose mean is the metric (the tuner sums them)
DEFAULT_EPS = 1e-2


def check_metrics(which) -> tuple[str, ...]:
    """`which` as a tuple of known metric names (an error names the unknown one)."""
    which = (which,) if isinstance(which, str) else tuple(which)
    for m in which:
        if m not in METRICS:
            raise OptionError(f"metrics: unknown metric {m!r}; use some of {', '.join(METRICS)}")
    if not which:
        raise OptionError(f"metrics: choose at least one of {', '.join(METRICS)}")
    return which


def evaluate(test, reference, display, ppd: float | None = None, eps: float = DEFAULT_EPS,
             names=("test", "reference"), which=IMAGE_METRICS, maps: bool = False, shown_reference=None,
             eccentricity=None):
    """The study's metrics of linear `test` against linear `reference`, each per view:
    ({metric: (views,) array}, {metric: (views, h, w) map} when `maps`).
    `eccentricity`: degrees of each pixel from its view's centre, (views, h, w) in the images' row
    order; the FOVEAL_METRICS need it.

    `display` (a fixed rayvr.study.display.Display) makes the displayed images that FLIP, PSNR
    and SSIM judge; HDR-FLIP and relMSE take the linear radiance. `ppd`: pixels per degree for
    both FLIPs (None: FLIP's 67). `shown_reference`: display(reference), when the caller keeps
    it for many tests (the same values; the study's metric pool does)."""
    t, r = pair(test, reference, names)
    which = check_metrics(which)
    need = set(which) | (set(MAP_METRICS) if maps else set())
    if need & set(FOVEAL_METRICS):
        if eccentricity is None or np.shape(eccentricity) != t.shape[:3]:
            raise OptionError(f"metrics {', '.join(FOVEAL_METRICS)}: need each pixel's eccentricity, (views, h, w) "
                              f"as the images (rayvr.xr.foveation.eccentricity_map of their views)")
        need.add("flip")
    if need & {"flip", "psnr", "ssim"}:
        shown = (display(t), display(r) if shown_reference is None else shown_reference)
    else:
        shown = None
    per_map = {}
    if "flip" in need:
        per_map["flip"] = flip_map(*shown, "ldr", ppd, names)
    if need & set(RELMSE_METRICS):
        per_map["relmse"] = rel_mse_map(t, r, eps, names)
    out = {}
    for m in which:
        if m == "relmse_trim":
            out[m] = np.array([trimmed_mean(view) for view in per_map["relmse"]])
        elif m == "fireflies":
            out[m] = firefly_map(t, r, eps, names).reshape(len(t), -1).sum(axis=1)
        elif m in per_map:
            out[m] = per_map[m].reshape(len(t), -1).mean(axis=1).astype(np.float64)
        elif m == "flip_fovea":
            out[m] = _foveal_mean(per_map["flip"], np.asarray(eccentricity) <= FOVEAL_RADIUS_DEG)
        elif m == "flip_ecc":
            out[m] = _foveal_mean(per_map["flip"], foveation.eccentricity_weight(eccentricity, FOVEAL_RADIUS_DEG))
        elif m == "hdrflip":
            out[m] = flip_map(t, r, "hdr", ppd, names).reshape(len(t), -1).mean(axis=1).astype(np.float64)
        elif m == "psnr":
            out[m] = np.array([psnr(shown[0][v], shown[1][v], 1.0, names) for v in range(len(t))])
        elif m == "ssim":
            out[m] = ssim_views(*shown, names)
    return out, (per_map if maps else {})


def _foveal_mean(error_map, weight) -> np.ndarray:
    """Per view, the mean of `error_map` weighted by `weight` (a mask or weights, (views, h, w))."""
    w = np.broadcast_to(np.asarray(weight, dtype=np.float64), error_map.shape).reshape(len(error_map), -1)
    e = error_map.reshape(len(error_map), -1).astype(np.float64)
    return (e * w).sum(axis=1) / np.maximum(w.sum(axis=1), 1e-30)


def all_metrics(test, reference, display, ppd: float | None = None, eps: float = DEFAULT_EPS,
                names=("test", "reference"), which=IMAGE_METRICS, eccentricity=None) -> dict:
    """`evaluate`'s metrics as one number each (the mean over views)."""
    per_view, _ = evaluate(test, reference, display, ppd, eps, names, which, eccentricity=eccentricity)
    return {m: float(np.mean(v)) for m, v in per_view.items()}
