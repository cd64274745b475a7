"""rayvr.tune.metrics against hand-computed values (no GPU)."""
import math

import numpy as np
import pytest

from rayvr.errors import OptionError, RayvrError
from rayvr.tune import metrics as M


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


def test_all_metrics_psnr_is_on_clamped_srgb():
    ref, test = image(4.0, (1, 8, 8, 3)), image(2.0, (1, 8, 8, 3))   # both clip to white
    out = M.all_metrics(test, ref)
    assert out["psnr"] == math.inf and out["relmse"] > 0 and out["flip"] > 0
    assert M.srgb_encode(np.array([0.0, 0.0031308, 1.0, 5.0])) == pytest.approx([0.0, 0.04045, 1.0, 1.0], abs=1e-4)
