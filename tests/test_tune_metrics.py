"""rayvr.study.metrics and rayvr.study.display against hand-computed values (no GPU)."""
import math

import numpy as np
import pytest

from rayvr.errors import OptionError, RayvrError
from rayvr.study import metrics as M
from rayvr.study.display import Display, clamp_negative, tonemap


def image(value, shape=(2, 8, 8, 4), dtype=np.float32):
    return np.full(shape, value, dtype=dtype)


def test_identical_images_have_zero_error_and_infinite_psnr():
    rng = np.random.default_rng(1)
    a = rng.random((2, 16, 16, 4)).astype(np.float32) * 3
    assert M.rel_mse(a, a) == 0.0
    assert M.psnr(a, a) == math.inf
    assert M.flip(a, a) == 0.0


def test_constant_offset_gives_exact_relmse_and_psnr():
    ref, test = image(0.5), image(0.6)
    # (0.1^2) / (0.5^2 + eps) per channel; alpha is ignored
    assert M.rel_mse(test, ref, eps=1e-2) == pytest.approx(0.01 / 0.26, rel=1e-6)
    assert M.rel_mse(test, ref, eps=0.75) == pytest.approx(0.01 / 1.0, rel=1e-6)
    assert M.psnr(test, ref, 1.0) == pytest.approx(20.0, abs=1e-4)       # 10 log10(1 / 0.01)
    assert M.psnr(test, ref, 2.0) == pytest.approx(20.0 + 20 * math.log10(2), abs=1e-4)


def test_uint8_psnr_uses_255_peak_and_own_units():
    ref = image(128, (16, 16, 3), np.uint8)
    test = ref + np.uint8(1)
    assert M.psnr(test, ref) == pytest.approx(20 * math.log10(255), abs=1e-9)   # MSE = 1


def test_relmse_map_is_per_pixel_and_its_mean_is_the_metric():
    ref = image(1.0, (1, 4, 4, 3))
    test = ref.copy()
    test[0, 1, 2] = 2.0                      # one pixel off by 1 in all channels
    m = M.rel_mse_map(test, ref, eps=1.0)
    assert m.shape == (1, 4, 4)
    assert m[0, 1, 2] == pytest.approx(0.5) and m.sum() == pytest.approx(0.5)
    assert M.rel_mse(test, ref, eps=1.0) == pytest.approx(0.5 / 16)


def test_flip_grows_with_the_difference_and_maps_per_view():
    ref = image(0.5, (2, 16, 16, 3))
    small, large = M.flip(ref * 1.05, ref), M.flip(ref * 2.0, ref)
    assert 0.0 < small < large <= 1.0
    fm = M.flip_map(ref * 2.0, ref)
    assert fm.shape == (2, 16, 16) and fm.mean() == pytest.approx(large, rel=1e-6)


def test_flip_ldr_for_integers_and_refuses_out_of_range_floats():
    a = image(100, (8, 8, 3), np.uint8)
    b = image(200, (8, 8, 3), np.uint8)
    assert M.flip(a, b) > 0.1 and M.flip(a, a) == 0.0
    with pytest.raises(OptionError, match="LDR"):
        M.flip(image(2.0, (8, 8, 3)), image(0.5, (8, 8, 3)), dynamic_range="ldr")


def test_flip_with_a_black_reference_does_not_end_the_process():
    black = image(0.0, (1, 8, 8, 3))
    assert M.flip(black, black) == 0.0
    assert M.flip(image(1.0, (1, 8, 8, 3)), black) > 0.5


@pytest.mark.parametrize("metric", [M.rel_mse, M.psnr, M.flip])
def test_nan_or_inf_is_an_error_naming_the_image_and_pixel(metric):
    ref, test = image(0.5), image(0.5)
    test[1, 3, 4, 2] = np.nan
    with pytest.raises(RayvrError, match=r"config 'X': 1 NaN/Inf value\(s\).*view 1, row 3, column 4, channel 2"):
        metric(test, ref, names=("config 'X'", "reference"))
    ref[0, 0, 0, 0] = np.inf
    with pytest.raises(RayvrError, match="reference: 1 NaN/Inf"):
        metric(image(0.5), ref)


def test_shape_and_option_errors():
    with pytest.raises(OptionError, match="same size"):
        M.rel_mse(image(0.5, (1, 8, 8, 3)), image(0.5, (1, 8, 4, 3)))
    with pytest.raises(OptionError, match="peak"):
        M.psnr(image(0.5), image(0.5), peak=0)
    with pytest.raises(OptionError, match="eps"):
        M.rel_mse(image(0.5), image(0.5), eps=0)
    with pytest.raises(OptionError, match="dynamic_range"):
        M.flip(image(0.5), image(0.5), dynamic_range="wide")
    with pytest.raises(RayvrError, match="negative"):
        M.flip(image(-0.5), image(0.5))


def test_shapes_hw_and_hwc_are_one_view():
    a = np.full((8, 8), 0.25, np.float32)
    assert M.as_views(a).shape == (1, 8, 8, 1)
    assert M.rel_mse(a, a * 2, eps=1.0) == pytest.approx(0.0625 / 1.25)


def test_srgb_encode_clamps_and_encodes():
    assert M.srgb_encode(np.array([0.0, 0.0031308, 1.0, 5.0])) == pytest.approx([0.0, 0.04045, 1.0, 1.0], abs=1e-4)


def test_evaluate_judges_the_displayed_image_and_the_radiance():
    ref = image(0.5, (2, 16, 16, 3))
    test = ref.copy()
    test[1] *= 1.2                                   # view 1 is 20% too bright
    display = Display("linear", 0.0)
    per_view, maps = M.evaluate(test, ref, display, ppd=14.0, maps=True)
    assert set(per_view) == set(M.IMAGE_METRICS) and all(v.shape == (2,) for v in per_view.values())   # no eccentricity: not the foveal ones
    assert per_view["flip"][0] == 0.0 and per_view["flip"][1] > 0.0
    assert per_view["relmse"][1] == pytest.approx(0.01 / (0.25 + M.DEFAULT_EPS), rel=1e-6)
    assert per_view["psnr"][0] == math.inf
    shown = tonemap(np.array([0.6]), "linear") - tonemap(np.array([0.5]), "linear")   # PSNR of the sRGB values
    assert per_view["psnr"][1] == pytest.approx(-20 * math.log10(abs(float(shown[0]))), rel=1e-6)
    assert per_view["ssim"][0] == pytest.approx(1.0) and per_view["ssim"][1] < 1.0
    assert maps["flip"].shape == (2, 16, 16) and maps["flip"][1].mean() == pytest.approx(per_view["flip"][1])
    # the exposure moves FLIP/PSNR/SSIM, never relMSE (linear radiance)
    darker, _ = M.evaluate(test, ref, Display("linear", -3.0), ppd=14.0)
    assert darker["relmse"] == pytest.approx(per_view["relmse"]) and darker["psnr"][1] > per_view["psnr"][1]


def test_all_metrics_is_the_mean_over_views_and_ssim_needs_7_pixels():
    ref = image(0.5, (2, 8, 8, 3))
    out = M.all_metrics(ref * 1.1, ref, Display("aces", 0.0), which=("relmse", "psnr"))
    assert set(out) == {"relmse", "psnr"} and out["relmse"] == pytest.approx(0.0025 / 0.26, rel=1e-6)
    with pytest.raises(OptionError, match="7x7 window"):
        M.ssim(image(0.5, (1, 6, 6, 3)), image(0.5, (1, 6, 6, 3)))
    with pytest.raises(OptionError, match="unknown metric 'mse'"):
        M.all_metrics(ref, ref, Display("aces", 0.0), which=("mse",))


def test_cpu_tonemap_follows_tonemap_comp():
    x = np.array([[0.0, 0.18, 1.0], [4.0, -1.0, np.nan]])
    aces = tonemap(x, "aces", 0.0)
    # Narkowicz's fit of 0.6 x, clamped, then sRGB; negative and NaN pixels are black
    y = 0.6 * 0.18
    expected = (y * (2.51 * y + 0.03)) / (y * (2.43 * y + 0.59) + 0.14)
    assert aces[0, 1] == pytest.approx(1.055 * expected ** (1 / 2.4) - 0.055)
    assert aces[0, 0] == 0.0 and np.all(aces[1] == 0.0)
    assert tonemap(np.array([1.0]), "reinhard", 1.0)[0] == pytest.approx(1.055 * (2 / 3) ** (1 / 2.4) - 0.055)
    assert tonemap(np.array([0.25]), "linear", 2.0)[0] == pytest.approx(1.0)


def test_negative_radiance_is_judged_as_the_display_shows_it():
    a = np.array([[[0.5, -0.25, 0.1, -1.0]]])                 # alpha is not radiance
    clamped, count = clamp_negative(a)
    assert count == 1 and clamped.tolist() == [[[0.5, 0.0, 0.1, -1.0]]] and a[0, 0, 1] == -0.25
    same, none = clamp_negative(clamped)
    assert none == 0 and same is clamped


def test_fixed_exposure_comes_from_the_reference_once():
    ref = np.full((1, 4, 4, 3), 0.045)                       # log2 mean luminance -> 0.18 at +2 stops
    ref[0, 0, 0] = 0.0                                         # black pixels do not count
    shown = Display("aces").fixed(ref)
    assert shown.exposure == pytest.approx(2.0)
    assert Display("aces", 0.5).fixed(ref).exposure == 0.5
    with pytest.raises(OptionError, match="not fixed"):
        Display("aces")(ref)
    with pytest.raises(OptionError, match="operator"):
        Display("filmic")


def test_trimmed_relmse_and_fireflies_see_past_a_few_outliers():
    """One pixel in 2,000 at 100x the reference: relMSE is ruled by it, the trimmed relMSE (the
    largest 0.1% left out) is the rest's exact error, and the firefly count finds that pixel."""
    ref = np.full((1, 40, 50, 3), 0.5)
    test = ref * 1.1                                      # every pixel 10% high: relMSE 0.0025/0.26
    test[0, 7, 9] = 50.0
    per_view, _ = M.evaluate(test, ref, Display().fixed(ref), which=("relmse", "relmse_trim", "fireflies"))
    exact = 0.05 ** 2 / (0.25 + 1e-2)
    assert per_view["relmse"][0] > 3.0                    # (49.5^2 / 0.26) / 2000 ~ 4.7
    assert per_view["relmse_trim"][0] == pytest.approx(exact, rel=1e-9)
    assert per_view["fireflies"][0] == 1
    # a black reference pixel: radiance above ~9 sqrt(eps) counts, noise below it does not
    dark = np.zeros((1, 8, 8, 3))
    noisy = np.full_like(dark, 0.5)
    noisy[0, 0, 0] = 2.0
    assert M.evaluate(noisy, dark, Display().fixed(np.ones_like(dark)), which=("fireflies",))[0]["fireflies"][0] == 1
    assert M.trimmed_mean(np.arange(10.0)) == pytest.approx(4.5)        # under 1000 values: nothing trimmed
    assert M.trimmed_mean(np.r_[np.zeros(999), 1e9]) == 0.0
